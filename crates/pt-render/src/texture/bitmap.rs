//! Bitmap textures (Mitsuba 3's `bitmap`): an image over texture coordinates.
//!
//! Lookup (Mitsuba 3.9.1, drjit's texture): the hit's uv goes through `to_uv` first; row 0 of
//! the image (its top row) is at v = 0; texel centres are at `((i + 0.5) / w, (j + 0.5) / h)`.
//! - `bilinear`: `p = uv * (w, h) - 0.5`, the four texels around `p` weighted by its fractional
//!   part, each wrapped on its own;
//! - `nearest`: texel `floor(uv * (w, h))`, wrapped.
//!
//! Wrap modes act on integer texel indices: `repeat` (`i mod n`), `clamp` (to `0..n-1`),
//! `mirror` (period `2n`, edge texels repeated: `m = i mod 2n`, `m` if `m < n`, else
//! `2n - 1 - m`).
//!
//! Decoding: 8- and 16-bit images (PNG, JPEG, BMP, TGA) are sRGB-decoded to linear values
//! unless `raw`; EXR and Radiance HDR are linear. Grey images are stored in all three
//! channels. Alpha is kept separately (glTF reads opacity from it; Mitsuba drops it).

use pt_math::Vec2;
use pt_scene::{BitmapFilter, ImageSource, TextureChannel, UvTransform, WrapMode};

/// A decoded image: linear RGB per texel, row-major from the top row, and its alpha channel
/// (linear, 1 where the file has none).
#[derive(Clone, Debug)]
pub struct Image {
    /// Width in texels.
    pub width: usize,
    /// Height in texels.
    pub height: usize,
    /// Linear RGB, row-major from the top row.
    pub texels: Vec<[f32; 3]>,
    /// Alpha per texel, if the file has an alpha channel.
    pub alpha: Option<Vec<f32>>,
}

/// The sRGB electro-optical transfer function (IEC 61966-2-1): encoded value in [0, 1] -> linear.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Whether a file holds linear values whatever `raw` says (EXR, Radiance HDR).
fn is_linear_format(source: &ImageSource) -> bool {
    match source {
        ImageSource::File(p) => matches!(
            p.extension()
                .and_then(|e| e.to_str())
                .map(str::to_ascii_lowercase)
                .as_deref(),
            Some("exr" | "hdr" | "rgbe")
        ),
        ImageSource::Embedded { .. } => false,
    }
}

impl Image {
    /// Decodes an image file or embedded image. 8- and 16-bit data are sRGB-decoded unless
    /// `raw`; EXR and HDR files are linear. Errors name the image.
    pub fn load(source: &ImageSource, raw: bool) -> Result<Image, String> {
        let name = source.short_name();
        let is_exr = matches!(source, ImageSource::File(p) if p.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("exr")));
        let img = if is_exr {
            let ImageSource::File(path) = source else {
                unreachable!("checked above")
            };
            let (img, _) = pt_image::read_exr(path).map_err(|e| e.to_string())?;
            Image {
                width: img.width as usize,
                height: img.height as usize,
                texels: img.data,
                alpha: None,
            }
        } else {
            let decoded = match source {
                ImageSource::File(p) => image::open(p)
                    .map_err(|e| format!("cannot read image '{}': {e}", p.display()))?,
                ImageSource::Embedded { bytes, .. } => image::load_from_memory(bytes)
                    .map_err(|e| format!("cannot decode {name}: {e}"))?,
            };
            let linear = raw || is_linear_format(source);
            let decode = |c: f32| if linear { c } else { srgb_to_linear(c) };
            let has_alpha = decoded.color().has_alpha();
            let rgba = decoded.to_rgba32f();
            let (w, h) = rgba.dimensions();
            Image {
                width: w as usize,
                height: h as usize,
                texels: rgba
                    .pixels()
                    .map(|p| [decode(p.0[0]), decode(p.0[1]), decode(p.0[2])])
                    .collect(),
                alpha: has_alpha.then(|| rgba.pixels().map(|p| p.0[3]).collect()),
            }
        };
        if img.width == 0 || img.height == 0 {
            return Err(format!("image {name} is empty"));
        }
        if img.texels.iter().any(|t| t.iter().any(|c| !c.is_finite())) {
            return Err(format!("image {name} has non-finite values"));
        }
        Ok(img)
    }

    /// One channel of the image (alpha: 1 where there is none) in all three channels.
    pub fn channel(&self, c: TextureChannel) -> Vec<[f32; 3]> {
        match c {
            TextureChannel::Red => self.texels.iter().map(|t| [t[0]; 3]).collect(),
            TextureChannel::Green => self.texels.iter().map(|t| [t[1]; 3]).collect(),
            TextureChannel::Blue => self.texels.iter().map(|t| [t[2]; 3]).collect(),
            TextureChannel::Alpha => match &self.alpha {
                Some(a) => a.iter().map(|&v| [v; 3]).collect(),
                None => vec![[1.0; 3]; self.texels.len()],
            },
        }
    }
}

/// Maps a texel index into `0..n` by the wrap mode (see the module docs).
#[inline(always)]
fn wrap_index(i: i64, n: i64, mode: WrapMode) -> usize {
    (match mode {
        WrapMode::Repeat => i.rem_euclid(n),
        WrapMode::Clamp => i.clamp(0, n - 1),
        WrapMode::Mirror => {
            let m = i.rem_euclid(2 * n);
            if m < n {
                m
            } else {
                2 * n - 1 - m
            }
        }
    }) as usize
}

/// How a bitmap is looked up: image size, filter, wrap mode and uv transform. Shared by the
/// RGB texels and their spectral forms, so both see the same texels with the same weights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lookup {
    /// Width in texels.
    pub width: usize,
    /// Height in texels.
    pub height: usize,
    /// Reconstruction between texels.
    pub filter: BitmapFilter,
    /// Wrapping outside [0, 1].
    pub wrap: WrapMode,
    /// Applied to the hit's uv first.
    pub to_uv: UvTransform,
}

/// Where a lookup reads: up to four texel indices and their weights (nearest: one texel of
/// weight 1, the others weight 0).
#[derive(Clone, Copy, Debug)]
pub struct Footprint {
    /// Row-major texel indices (00, 10, 01, 11).
    pub texels: [usize; 4],
    /// Bilinear weights, summing to 1.
    pub weights: [f32; 4],
}

impl Lookup {
    /// The texels and weights of a lookup at the surface's texture coordinates `uv`.
    #[inline(always)]
    pub fn footprint(&self, uv: Vec2) -> Footprint {
        let m = self.to_uv;
        let (u, v) = (
            m[0] * uv.x + m[1] * uv.y + m[2],
            m[3] * uv.x + m[4] * uv.y + m[5],
        );
        let (w, h) = (self.width as i64, self.height as i64);
        let (x, y) = (u * self.width as f32, v * self.height as f32);
        let at = |xi: i64, yi: i64| {
            wrap_index(yi, h, self.wrap) * self.width + wrap_index(xi, w, self.wrap)
        };
        if self.filter == BitmapFilter::Nearest {
            let t = at(x.floor() as i64, y.floor() as i64);
            return Footprint {
                texels: [t; 4],
                weights: [1.0, 0.0, 0.0, 0.0],
            };
        }
        let (x, y) = (x - 0.5, y - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (xi, yi) = (x0 as i64, y0 as i64);
        Footprint {
            texels: [
                at(xi, yi),
                at(xi + 1, yi),
                at(xi, yi + 1),
                at(xi + 1, yi + 1),
            ],
            weights: [
                (1.0 - fx) * (1.0 - fy),
                fx * (1.0 - fy),
                (1.0 - fx) * fy,
                fx * fy,
            ],
        }
    }
}

/// An RGB bitmap with its lookup: linear values at texture coordinates.
#[derive(Clone, Debug)]
pub struct Bitmap {
    /// How it is looked up.
    pub lookup: Lookup,
    /// Linear RGB texels, row-major from the top row.
    pub texels: Vec<[f32; 3]>,
}

impl Bitmap {
    /// Linear RGB at the surface's texture coordinates `uv`.
    #[cfg_attr(debug_assertions, inline)]
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn eval(&self, uv: Vec2) -> [f32; 3] {
        let f = self.lookup.footprint(uv);
        let t = f.texels.map(|i| self.texels[i]);
        let w = f.weights;
        std::array::from_fn(|k| {
            (t[0][k] * w[0] + t[1][k] * w[1]) + (t[2][k] * w[2] + t[3][k] * w[3])
        })
    }

    /// The uv gradient of the scalar value (each texel's luminance) at `uv`, per unit of the
    /// surface's uv (Mitsuba 3.9.1's `eval_1_grad`): the derivative of the bilinear
    /// interpolation in texel units, `df/dx = (1 - fy)(f10 - f00) + fy (f11 - f01)` and
    /// `df/dy = (1 - fx)(f01 - f00) + fx (f11 - f10)`, taken through the transpose of `to_uv`'s
    /// linear part and then scaled by the resolution, `(W, H) * (M^T (df/dx, df/dy))`, in that
    /// order as Mitsuba does (the exact chain rule scales before the transpose; the two agree
    /// unless `to_uv` rotates a non-square image). Nearest-neighbour lookups have gradient 0.
    pub fn gradient_1(&self, uv: Vec2) -> Vec2 {
        if self.lookup.filter == BitmapFilter::Nearest {
            return Vec2::ZERO;
        }
        let f = self.lookup.footprint(uv);
        let [f00, f10, f01, f11] = f.texels.map(|i| super::luminance(self.texels[i]));
        // The weights are (1-fx)(1-fy), fx(1-fy), (1-fx)fy, fx fy.
        let fx = f.weights[1] + f.weights[3];
        let fy = f.weights[2] + f.weights[3];
        let dx = (1.0 - fy) * (f10 - f00) + fy * (f11 - f01);
        let dy = (1.0 - fx) * (f01 - f00) + fx * (f11 - f10);
        let m = self.lookup.to_uv;
        Vec2::new(
            self.lookup.width as f32 * (m[0] * dx + m[3] * dy),
            self.lookup.height as f32 * (m[1] * dx + m[4] * dy),
        )
    }

    /// Mean of each channel over the texels (for light power and sampling weights).
    pub fn mean(&self) -> [f32; 3] {
        let mut acc = [0.0f64; 3];
        for t in &self.texels {
            for c in 0..3 {
                acc[c] += f64::from(t[c]);
            }
        }
        let n = self.texels.len().max(1) as f64;
        acc.map(|a| (a / n) as f32)
    }

    /// The same image with every texel replaced by `f(texel)`.
    pub fn map_texels(&self, f: impl Fn([f32; 3]) -> [f32; 3]) -> Bitmap {
        Bitmap {
            lookup: self.lookup,
            texels: self.texels.iter().map(|&t| f(t)).collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    /// The gradient of a bilinear lookup of a linear ramp f = a x + b y (x, y texel indices)
    /// is (a W s_u, b H s_v) per unit uv inside the image, for `to_uv` scales (s_u, s_v): the
    /// texel-to-uv scale and the transform's chain rule. Nearest lookups have no gradient.
    #[test]
    fn gradient_of_a_ramp_is_its_slope_per_unit_uv() {
        let (w, h, a, b) = (8usize, 5usize, 0.03f32, -0.05f32);
        let texels = (0..w * h)
            .map(|i| [a * (i % w) as f32 + b * (i / w) as f32 + 0.5; 3])
            .collect();
        let mut bitmap = Bitmap {
            lookup: Lookup {
                width: w,
                height: h,
                filter: BitmapFilter::Bilinear,
                wrap: WrapMode::Clamp,
                to_uv: [2.0, 0.0, 0.1, 0.0, 3.0, 0.05],
            },
            texels,
        };
        for uv in [
            Vec2::new(0.2, 0.1),
            Vec2::new(0.31, 0.22),
            Vec2::new(0.4, 0.27),
        ] {
            let g = bitmap.gradient_1(uv);
            let want = Vec2::new(a * w as f32 * 2.0, b * h as f32 * 3.0);
            assert!(
                (g - want).length() < 1e-4 * want.length(),
                "{uv}: {g} vs {want}"
            );
        }
        bitmap.lookup.filter = BitmapFilter::Nearest;
        assert_eq!(bitmap.gradient_1(Vec2::new(0.2, 0.1)), Vec2::ZERO);
    }

    use super::*;
    use pt_scene::UV_IDENTITY;

    fn strip(values: &[f32], filter: BitmapFilter, wrap: WrapMode) -> Bitmap {
        Bitmap {
            lookup: Lookup {
                width: values.len(),
                height: 1,
                filter,
                wrap,
                to_uv: UV_IDENTITY,
            },
            texels: values.iter().map(|&v| [v; 3]).collect(),
        }
    }

    #[test]
    fn bilinear_between_centres_and_repeat() {
        let b = strip(&[0.0, 1.0], BitmapFilter::Bilinear, WrapMode::Repeat);
        assert_eq!(b.eval(Vec2::new(0.25, 0.5))[0], 0.0); // centre of texel 0
        assert_eq!(b.eval(Vec2::new(0.75, 0.5))[0], 1.0); // centre of texel 1
        assert!((b.eval(Vec2::new(0.5, 0.5))[0] - 0.5).abs() < 1e-6);
        assert!(
            (b.eval(Vec2::new(0.0, 0.5))[0] - 0.5).abs() < 1e-6,
            "wraps to the other edge"
        );
        assert!((b.eval(Vec2::new(1.25, 0.5))[0]).abs() < 1e-6, "repeats");
        assert!(
            (srgb_to_linear(1.0) - 1.0).abs() < 1e-6 && (srgb_to_linear(0.5) - 0.214).abs() < 1e-3
        );
    }

    #[test]
    fn wrap_modes_follow_mitsuba() {
        // Mitsuba's mirror for n = 4, i = -5..8: 3,3,2,1,0 | 0,1,2,3 | 3,2,1,0 | 0.
        let mirror: Vec<usize> = (-5..9)
            .map(|i| wrap_index(i, 4, WrapMode::Mirror))
            .collect();
        assert_eq!(mirror, [3, 3, 2, 1, 0, 0, 1, 2, 3, 3, 2, 1, 0, 0]);
        let clamp: Vec<usize> = (-2..6).map(|i| wrap_index(i, 4, WrapMode::Clamp)).collect();
        assert_eq!(clamp, [0, 0, 0, 1, 2, 3, 3, 3]);
        // Left of the first centre: clamp holds texel 0, repeat blends with the last texel.
        let v = [0.0, 0.5, 1.0];
        let clamped = strip(&v, BitmapFilter::Bilinear, WrapMode::Clamp);
        let repeated = strip(&v, BitmapFilter::Bilinear, WrapMode::Repeat);
        assert_eq!(clamped.eval(Vec2::new(0.05, 0.5))[0], 0.0);
        assert!(repeated.eval(Vec2::new(0.05, 0.5))[0] > 0.3);
        // Beyond the right edge, mirror comes back down; clamp stays at the edge value.
        let mirrored = strip(&v, BitmapFilter::Nearest, WrapMode::Mirror);
        assert_eq!(mirrored.eval(Vec2::new(1.1, 0.5))[0], 1.0);
        assert_eq!(mirrored.eval(Vec2::new(1.5, 0.5))[0], 0.5);
        assert_eq!(clamped.eval(Vec2::new(1.5, 0.5))[0], 1.0);
    }

    #[test]
    fn nearest_takes_the_texel_the_point_falls_in_and_to_uv_applies_first() {
        let mut b = strip(
            &[0.1, 0.2, 0.3, 0.4],
            BitmapFilter::Nearest,
            WrapMode::Repeat,
        );
        assert_eq!(b.eval(Vec2::new(0.49, 0.5))[0], 0.2);
        assert_eq!(b.eval(Vec2::new(0.5, 0.5))[0], 0.3);
        // to_uv scales u by 2: u = 0.3 reads at 0.6.
        b.lookup.to_uv = [2.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        assert_eq!(b.eval(Vec2::new(0.3, 0.5))[0], 0.3);
    }
}
