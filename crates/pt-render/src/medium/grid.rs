//! Spatially varying medium parameters: Mitsuba 3.9.1's `gridvolume` (a grid of one or three
//! channels) and `constvolume`, placed in world space.
//!
//! Lookups follow Mitsuba's `gridvolume`: values sit at cell centres of the grid's unit cube
//! (cell `i` of `n` at `(i + 0.5) / n`), blended trilinearly (or taken from the nearest cell),
//! and points outside the cube take the value at the nearest point of its border (Mitsuba's
//! default `wrap_mode`, clamp). A medium only evaluates its extinction grid inside the grid's
//! box (the medium's extent); an albedo or emission grid may be looked up anywhere.
//!
//! Three channels are RGB. In RGB mode they are blended as they are. In spectral mode each
//! cell is stored as Mitsuba stores it: the cell's colour divided by `s = 2 max(r, g, b)`,
//! upsampled to a smooth spectrum in [0, 1] (Jakob & Hanika 2019, through the shared
//! coefficient table), and `s`; a lookup blends the eight spectra and, separately, the eight
//! scales, and multiplies the two (which is not the blend of the products: it is Mitsuba's).

use crate::texture::ConstantSpectrum;
use pt_math::{Mat4, Vec3, Vec4};
use pt_spectrum::{srgb_to_sigmoid, RgbSigmoid, SampledSpectrum, SampledWavelengths, Spectrum};

/// A grid of values over its unit cube, placed in world space (see the module documentation).
#[derive(Clone, Debug)]
pub struct Grid {
    cells: Cells,
    resolution: [usize; 3],
    nearest: bool,
    /// World space to the grid's unit cube.
    world_to_grid: Mat4,
    /// Spectral emission grids: the illuminant (D65 of unit luminance) their upsampled
    /// colours are multiplied by, as an RGB emission is in spectral mode.
    tint: Option<Spectrum>,
    /// An upper bound of every value the grid returns in any channel or at any wavelength:
    /// the largest stored value (RGB, one channel), or the largest scale `2 max(r, g, b)`
    /// (spectral: the upsampled spectra lie in [0, 1]). With the extinction factor, the
    /// majorant of delta and ratio tracking. For a tinted grid, without the tint.
    pub max: f32,
}

/// The stored cells, x fastest, then y, then z.
#[derive(Clone, Debug)]
enum Cells {
    /// One value per cell: the same in every channel.
    Scalar(Vec<f32>),
    /// RGB mode, three channels: the colour per cell.
    Rgb(Vec<[f32; 3]>),
    /// Spectral mode, three channels: per cell the spectrum of `rgb / s` and `s = 2 max(rgb)`.
    Spectral(Vec<(RgbSigmoid, f32)>),
}

/// Where a lookup falls: the nearest cell, or the eight cells around the point (x fastest, then
/// y, then z) and the point's position between them, each in [0, 1].
enum Footprint {
    Cell(usize),
    Trilinear { corner: [usize; 8], w: Vec3 },
}

/// The cells a lookup blends and their weights (trilinear: eight; nearest: one, weight 1).
struct Stencil {
    index: [usize; 8],
    weight: [f32; 8],
    count: usize,
}

impl Grid {
    /// A grid over `values` (`channels` per cell, 1 or 3; x fastest) of `resolution` cells,
    /// placed by `to_world` (the unit cube to world space; invertible). Three channels are
    /// linear sRGB, kept as they are in `ColorMode::Rgb` and upsampled per cell otherwise
    /// (`spectral`); `emission` marks an emitted quantity, which spectral mode multiplies by
    /// D65 (as any RGB emission). Returns `None` for another channel count or a value count
    /// that does not match.
    pub fn new(
        values: &[f32],
        channels: u32,
        resolution: [u32; 3],
        to_world: Mat4,
        nearest: bool,
        spectral: bool,
        emission: bool,
    ) -> Option<Self> {
        let n: usize = resolution.iter().map(|&r| r as usize).product();
        if n == 0 || values.len() != n * channels as usize {
            return None;
        }
        let clean = |v: f32| if v.is_finite() { v.max(0.0) } else { 0.0 };
        let (cells, max) = match channels {
            1 => {
                let cells: Vec<f32> = values.iter().map(|&v| clean(v)).collect();
                let max = cells.iter().copied().fold(0.0, f32::max);
                (Cells::Scalar(cells), max)
            }
            3 => {
                let rgb = values
                    .chunks_exact(3)
                    .map(|c| [clean(c[0]), clean(c[1]), clean(c[2])]);
                if spectral {
                    let cells: Vec<(RgbSigmoid, f32)> = rgb
                        .map(|c| {
                            let s = 2.0 * c[0].max(c[1]).max(c[2]);
                            if s > 0.0 {
                                (srgb_to_sigmoid(c.map(|v| v / s)), s)
                            } else {
                                (RgbSigmoid::constant(0.0), 0.0)
                            }
                        })
                        .collect();
                    let max = cells.iter().map(|c| c.1).fold(0.0, f32::max);
                    (Cells::Spectral(cells), max)
                } else {
                    let cells: Vec<[f32; 3]> = rgb.collect();
                    let max = cells.iter().flatten().copied().fold(0.0, f32::max);
                    (Cells::Rgb(cells), max)
                }
            }
            _ => return None,
        };
        let tint = (emission && spectral && channels == 3)
            .then(|| Spectrum::illuminant(pt_spectrum::NamedIlluminant::D65, 1.0));
        Some(Grid {
            cells,
            resolution: resolution.map(|r| r as usize),
            nearest,
            world_to_grid: to_world.inverse(),
            tint,
            max,
        })
    }

    /// The cells a lookup at the world point `p` reads.
    #[cfg_attr(debug_assertions, inline)]
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn footprint(&self, p: Vec3) -> Footprint {
        let g = self.world_to_grid.transform_point3(p);
        let [nx, ny, nz] = self.resolution;
        let res = Vec3::new(nx as f32, ny as f32, nz as f32);
        let at = |x: usize, y: usize, z: usize| (z * ny + y) * nx + x;
        if self.nearest {
            let c = (g * res).floor().min(res - Vec3::ONE).max(Vec3::ZERO);
            return Footprint::Cell(at(c.x as usize, c.y as usize, c.z as usize));
        }
        // Cell centres at (i + 0.5) / n: the continuous index of p is g n - 0.5, clamped (also
        // for points outside the cube: Mitsuba's clamp). NaN clamps to 0.
        let f = (g * res - Vec3::splat(0.5))
            .max(Vec3::ZERO)
            .min(res - Vec3::ONE);
        let i = f.floor();
        let (x0, y0, z0) = (i.x as usize, i.y as usize, i.z as usize);
        let (x1, y1, z1) = (
            (x0 + 1).min(nx - 1),
            (y0 + 1).min(ny - 1),
            (z0 + 1).min(nz - 1),
        );
        Footprint::Trilinear {
            corner: [
                at(x0, y0, z0),
                at(x1, y0, z0),
                at(x0, y1, z0),
                at(x1, y1, z0),
                at(x0, y0, z1),
                at(x1, y0, z1),
                at(x0, y1, z1),
                at(x1, y1, z1),
            ],
            w: f - i,
        }
    }

    /// The cells blended at the world point `p` and their weights.
    #[cfg_attr(debug_assertions, inline)]
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn stencil(&self, p: Vec3) -> Stencil {
        match self.footprint(p) {
            Footprint::Cell(i) => Stencil {
                index: [i; 8],
                weight: [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                count: 1,
            },
            Footprint::Trilinear { corner, w } => {
                let (u, v, t) = (w.x, w.y, w.z);
                Stencil {
                    index: corner,
                    weight: [
                        (1.0 - u) * (1.0 - v) * (1.0 - t),
                        u * (1.0 - v) * (1.0 - t),
                        (1.0 - u) * v * (1.0 - t),
                        u * v * (1.0 - t),
                        (1.0 - u) * (1.0 - v) * t,
                        u * (1.0 - v) * t,
                        (1.0 - u) * v * t,
                        u * v * t,
                    ],
                    count: 8,
                }
            }
        }
    }

    /// A one-channel lookup as nested lerps (the hot path of delta and ratio tracking through
    /// density grids: the stencil's blend without its weight arrays).
    #[cfg_attr(debug_assertions, inline)]
    #[cfg_attr(not(debug_assertions), inline(always))]
    fn lookup_scalar(&self, c: &[f32], p: Vec3) -> f32 {
        match self.footprint(p) {
            Footprint::Cell(i) => c[i],
            Footprint::Trilinear { corner, w } => {
                let v = corner.map(|i| c[i]);
                let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
                let (c00, c10) = (lerp(v[0], v[1], w.x), lerp(v[2], v[3], w.x));
                let (c01, c11) = (lerp(v[4], v[5], w.x), lerp(v[6], v[7], w.x));
                lerp(lerp(c00, c10, w.y), lerp(c01, c11, w.y), w.z)
            }
        }
    }

    /// The value at the world point `p` at the path's wavelengths (RGB mode: per channel,
    /// fourth lane 0; a one-channel grid: the same value in every lane).
    #[cfg_attr(debug_assertions, inline)]
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn at(&self, p: Vec3, lambda: &SampledWavelengths) -> SampledSpectrum {
        let v = match &self.cells {
            Cells::Scalar(c) => return SampledSpectrum::splat(self.lookup_scalar(c, p)),
            Cells::Rgb(c) => {
                let s = self.stencil(p);
                let mut sum = Vec4::ZERO;
                for k in 0..s.count {
                    let [r, g, b] = c[s.index[k]];
                    sum += Vec4::new(r, g, b, 0.0) * s.weight[k];
                }
                sum
            }
            Cells::Spectral(c) => {
                let s = self.stencil(p);
                let l = lambda.lambda();
                let (mut spectrum, mut scale) = (Vec4::ZERO, 0.0f32);
                for k in 0..s.count {
                    let (sigmoid, cell_scale) = &c[s.index[k]];
                    spectrum += sigmoid.eval4(l) * s.weight[k];
                    scale += cell_scale * s.weight[k];
                }
                spectrum * scale
            }
        };
        let v = SampledSpectrum(v);
        match &self.tint {
            Some(t) => v * t.sample(lambda),
            None => v,
        }
    }

    /// The interval of `ray`'s parameter in which it is inside the grid's cube, clipped to
    /// `[ray.tmin, tmax]`; `None` if it misses. The parameter is the world one (an affine map
    /// keeps it).
    #[inline]
    pub fn clip(&self, ray: &pt_math::Ray, tmax: f32) -> Option<(f32, f32)> {
        let o = self.world_to_grid.transform_point3(ray.origin);
        let d = self.world_to_grid.transform_vector3(ray.dir);
        let inv = d.recip();
        let (a, b) = ((Vec3::ZERO - o) * inv, (Vec3::ONE - o) * inv);
        let (lo, hi) = (a.min(b), a.max(b));
        // NaN (a zero direction component with o on a face) counts as no bound.
        let t0 = [lo.x, lo.y, lo.z, ray.tmin]
            .into_iter()
            .fold(f32::NEG_INFINITY, |m, x| if x > m { x } else { m });
        let t1 = [hi.x, hi.y, hi.z, tmax]
            .into_iter()
            .fold(f32::INFINITY, |m, x| if x < m { x } else { m });
        (t0 < t1).then_some((t0, t1))
    }
}

/// A medium parameter that may vary in space: a constant (Mitsuba's plain spectrum or
/// `constvolume`) or a grid (`gridvolume`).
#[derive(Clone, Debug)]
pub enum VolumeSpectrum {
    /// The same value everywhere.
    Constant(ConstantSpectrum),
    /// A grid's value at the point.
    Grid(Grid),
}

impl VolumeSpectrum {
    /// The value at the world point `p` at the path's wavelengths.
    #[cfg_attr(debug_assertions, inline)]
    #[cfg_attr(not(debug_assertions), inline(always))]
    pub fn at(&self, p: Vec3, lambda: &SampledWavelengths) -> SampledSpectrum {
        match self {
            VolumeSpectrum::Constant(c) => c.at(lambda),
            VolumeSpectrum::Grid(g) => g.at(p, lambda),
        }
    }

    /// The constant value, if it does not vary in space.
    #[inline]
    pub fn constant(&self) -> Option<&ConstantSpectrum> {
        match self {
            VolumeSpectrum::Constant(c) => Some(c),
            VolumeSpectrum::Grid(_) => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2 x 1 x 1 RGB grid over [0, 2] x [0, 1] x [0, 1]: lookups at the cell centres give
    /// the cells' colours, halfway between them the mean, and points outside the cube the
    /// value at the nearest border point (Mitsuba's clamp), in RGB mode exactly.
    #[test]
    fn rgb_lookups_blend_and_clamp() {
        let values = [0.2, 0.4, 0.6, 1.0, 0.0, 0.5];
        let to_world = Mat4::from_scale(Vec3::new(2.0, 1.0, 1.0));
        let g = Grid::new(&values, 3, [2, 1, 1], to_world, false, false, false).unwrap();
        // RGB cells ignore the wavelengths.
        let lambda = SampledWavelengths::sample_visible(0.5);
        let at = |x: f32| g.at(Vec3::new(x, 0.5, 0.5), &lambda).0.to_array();
        let close = |a: [f32; 4], b: [f32; 3]| (0..3).all(|i| (a[i] - b[i]).abs() < 1e-6);
        assert!(close(at(0.5), [0.2, 0.4, 0.6]));
        assert!(close(at(1.5), [1.0, 0.0, 0.5]));
        assert!(close(at(1.0), [0.6, 0.2, 0.55]));
        assert!(close(at(-3.0), [0.2, 0.4, 0.6]), "clamped below");
        assert!(close(at(7.0), [1.0, 0.0, 0.5]), "clamped above");
        assert_eq!(g.max, 1.0);
    }

    /// Spectral mode keeps Mitsuba's split of a cell into a [0, 1] spectrum and a scale: at a
    /// cell centre a grey cell gives its value at every wavelength, and halfway between two
    /// cells the product of the blended spectra and the blended scales (not the blend of the
    /// products). The bound `max` holds at random wavelengths.
    #[test]
    fn spectral_cells_blend_spectrum_and_scale_apart() {
        let values = [0.3, 0.3, 0.3, 4.0, 4.0, 4.0];
        let to_world = Mat4::from_scale(Vec3::new(2.0, 1.0, 1.0));
        let g = Grid::new(&values, 3, [2, 1, 1], to_world, false, true, false).unwrap();
        let lambda = SampledWavelengths::sample_visible(0.37);
        let at = |x: f32| g.at(Vec3::new(x, 0.5, 0.5), &lambda).0.to_array();
        for v in at(0.5) {
            assert!((v - 0.3).abs() < 1e-5, "{v}");
        }
        // Both spectra are the constant 0.5; the scales 0.6 and 8 blend to 4.3: 2.15.
        for v in at(1.0) {
            assert!((v - 2.15).abs() < 1e-5, "{v}");
        }
        assert_eq!(g.max, 8.0);
        let coloured = Grid::new(
            &[0.9, 0.1, 0.0],
            3,
            [1, 1, 1],
            Mat4::IDENTITY,
            false,
            true,
            false,
        )
        .unwrap();
        for u in [0.01, 0.3, 0.77, 0.99] {
            let l = SampledWavelengths::sample_visible(u);
            let v = coloured.at(Vec3::splat(0.5), &l).0.to_array();
            assert!(
                v.iter().all(|&x| (0.0..=coloured.max).contains(&x)),
                "{v:?}"
            );
        }
    }

    /// Nearest lookups take the cell that holds the point; a wrong channel count or value
    /// count is refused.
    #[test]
    fn nearest_cells_and_bad_shapes() {
        let g = Grid::new(
            &[1.0, 2.0, 3.0],
            1,
            [3, 1, 1],
            Mat4::IDENTITY,
            true,
            false,
            false,
        )
        .unwrap();
        let l = SampledWavelengths::sample_visible(0.5);
        let at = |x: f32| g.at(Vec3::new(x, 0.5, 0.5), &l).0.x;
        assert_eq!(at(0.1), 1.0);
        assert_eq!(at(0.5), 2.0);
        assert_eq!(at(0.99), 3.0);
        assert!(Grid::new(&[1.0; 6], 6, [1, 1, 1], Mat4::IDENTITY, true, false, false).is_none());
        assert!(Grid::new(&[1.0; 5], 1, [2, 2, 1], Mat4::IDENTITY, true, false, false).is_none());
    }
}
