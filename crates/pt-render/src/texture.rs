//! Bitmap textures (Mitsuba's `bitmap`): an image over `[0,1]^2` texture coordinates, with row 0
//! at v = 0 (the image's top row), repeated outside `[0,1]`, bilinearly interpolated between pixel
//! centres (or nearest). 8-bit images are sRGB-decoded to linear values unless `raw`.

use pt_math::Vec2;
use pt_scene::BitmapDesc;
use std::path::Path;

/// A loaded image in linear RGB.
#[derive(Clone, Debug)]
pub struct Bitmap {
    width: usize,
    height: usize,
    texels: Vec<[f32; 3]>,
    nearest: bool,
}

/// The sRGB electro-optical transfer function (IEC 61966-2-1): 8-bit code value / 255 -> linear.
fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Decodes an image given by file or embedded bytes (PNG or JPEG); a message naming it when it
/// cannot be read or has no pixels.
fn decode_source(source: &pt_scene::ImageSource) -> Result<image::DynamicImage, String> {
    let (img, name) = match source {
        pt_scene::ImageSource::File(p) => (
            image::open(p).map_err(|e| format!("cannot read image '{}': {e}", p.display()))?,
            p.display().to_string(),
        ),
        pt_scene::ImageSource::Embedded { name, bytes } => (
            image::load_from_memory(bytes).map_err(|e| format!("cannot decode {name}: {e}"))?,
            name.clone(),
        ),
    };
    if img.width() == 0 || img.height() == 0 {
        return Err(format!("image {name} is empty"));
    }
    Ok(img)
}

impl Bitmap {
    /// Loads a PNG or JPEG (through the `image` crate) or an EXR (already linear).
    pub fn load(desc: &BitmapDesc) -> Result<Bitmap, String> {
        let path: &Path = &desc.filename;
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        let (width, height, texels) = if ext == "exr" {
            let (img, _) = pt_image::read_exr(path).map_err(|e| e.to_string())?;
            (img.width as usize, img.height as usize, img.data)
        } else {
            let img = decode_source(&pt_scene::ImageSource::File(path.to_path_buf()))?.to_rgb32f();
            let (w, h) = img.dimensions();
            let decode = |c: f32| if desc.raw { c } else { srgb_to_linear(c) };
            let texels = img
                .pixels()
                .map(|p| [decode(p.0[0]), decode(p.0[1]), decode(p.0[2])])
                .collect();
            (w as usize, h as usize, texels)
        };
        if width == 0 || height == 0 {
            return Err(format!("image '{}' is empty", path.display()));
        }
        if texels
            .iter()
            .any(|t: &[f32; 3]| t.iter().any(|c| !c.is_finite() || *c < 0.0))
        {
            return Err(format!(
                "image '{}' has negative or non-finite values",
                path.display()
            ));
        }
        Ok(Bitmap {
            width,
            height,
            texels,
            nearest: desc.filter == "nearest",
        })
    }

    /// Decodes an image given by file or by embedded bytes (glTF textures): PNG or JPEG through
    /// the `image` crate; `srgb` decodes sRGB-encoded values to linear, otherwise values are
    /// used as stored (normalised to [0, 1]).
    pub fn from_source(
        source: &pt_scene::ImageSource,
        srgb: bool,
        nearest: bool,
    ) -> Result<Bitmap, String> {
        let img = decode_source(source)?;
        let img = img.to_rgb32f();
        let (w, h) = img.dimensions();
        let decode = |c: f32| if srgb { srgb_to_linear(c) } else { c };
        let texels = img
            .pixels()
            .map(|p| [decode(p.0[0]), decode(p.0[1]), decode(p.0[2])])
            .collect();
        Ok(Bitmap {
            width: w as usize,
            height: h as usize,
            texels,
            nearest,
        })
    }

    /// The alpha channel of an image given by file or embedded bytes (glTF base colour alpha),
    /// as stored (alpha is linear in glTF), in all three channels; 1 where the image has none.
    pub fn alpha_from_source(
        source: &pt_scene::ImageSource,
        nearest: bool,
    ) -> Result<Bitmap, String> {
        let img = decode_source(source)?;
        let img = img.to_rgba32f();
        let (w, h) = img.dimensions();
        let texels = img.pixels().map(|p| [p.0[3]; 3]).collect();
        Ok(Bitmap {
            width: w as usize,
            height: h as usize,
            texels,
            nearest,
        })
    }

    /// Linear RGB at texture coordinates `uv`.
    pub fn eval(&self, uv: Vec2) -> [f32; 3] {
        let (w, h) = (self.width as i64, self.height as i64);
        let x = uv.x * self.width as f32 - 0.5;
        let y = uv.y * self.height as f32 - 0.5;
        let at = |xi: i64, yi: i64| self.texels[(yi.rem_euclid(h) * w + xi.rem_euclid(w)) as usize];
        if self.nearest {
            return at(x.round() as i64, y.round() as i64);
        }
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (xi, yi) = (x0 as i64, y0 as i64);
        let (a, b, c, d) = (
            at(xi, yi),
            at(xi + 1, yi),
            at(xi, yi + 1),
            at(xi + 1, yi + 1),
        );
        std::array::from_fn(|k| {
            (a[k] * (1.0 - fx) + b[k] * fx) * (1.0 - fy) + (c[k] * (1.0 - fx) + d[k] * fx) * fy
        })
    }

    /// Mean luminance (Rec. 709 Y) of the texels, for light selection.
    pub fn mean_luminance(&self) -> f32 {
        let sum: f64 = self
            .texels
            .iter()
            .map(|t| (0.212_671 * t[0] + 0.715_160 * t[1] + 0.072_169 * t[2]) as f64)
            .sum();
        (sum / self.texels.len() as f64) as f32
    }
}

/// Raw access for the spectral forms of an image (`spectral_texture.rs`), which must look up the
/// same texels with the same weights as [`Bitmap::eval`].
impl Bitmap {
    /// Width and height in texels.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// Linear RGB texels, row-major from the top row (v = 0).
    pub fn texels(&self) -> &[[f32; 3]] {
        &self.texels
    }

    /// Whether lookups take the nearest texel instead of interpolating bilinearly.
    pub fn is_nearest(&self) -> bool {
        self.nearest
    }

    /// The same image with every texel (linear values) replaced by `f(texel)`.
    pub fn map_texels(&self, f: impl Fn([f32; 3]) -> [f32; 3]) -> Bitmap {
        Bitmap {
            width: self.width,
            height: self.height,
            texels: self.texels.iter().map(|&t| f(t)).collect(),
            nearest: self.nearest,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bilinear_between_centres_and_repeat() {
        let b = Bitmap {
            width: 2,
            height: 1,
            texels: vec![[0.0; 3], [1.0; 3]],
            nearest: false,
        };
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
}
