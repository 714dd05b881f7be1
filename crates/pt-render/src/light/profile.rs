//! Intensity profiles: how a point-like light's radiant intensity varies over directions (IES
//! photometric files, pbrt-v4's `goniometric` image), evaluated, sampled and integrated.
//!
//! The profile is the table of `pt_scene::IntensityTable`: values at nodes (theta_i, phi_j),
//! theta the polar angle from the table's pole and phi the azimuth around it, bilinear in
//! (theta, phi) inside each cell, zero outside the first and last row, periodic in phi.
//!
//! **Sampling** (for rays leaving the light). A cell is chosen with probability proportional to
//! `b_k Omega_k`, `Omega_k = (phi_j+1 - phi_j)(cos theta_i - cos theta_i+1)` its solid angle and
//! `b_k` the largest of its four corner values, which bounds the bilinear values inside it (times,
//! for a spot, the cone's falloff at the cell's smaller polar angle, which bounds the falloff
//! there since it decreases away from the axis). Inside the cell, phi and cos theta are uniform,
//! so the direction is uniform in solid angle over the cell and its density is
//! `b_k / sum_k(b_k Omega_k)`: piecewise constant, positive wherever the intensity is (a
//! corner of every cell with positive values is positive), and evaluated exactly by `pdf`. The
//! estimator's weight `I(d) / p(d)` is then at most the sum, and at its best for smooth
//! profiles whose cells are small.

use pt_math::{Distribution1D, Mat3, Vec2, Vec3};
use pt_scene::IntensityTable;
use std::f32::consts::TAU;

use super::SpotCone;

/// A tabulated intensity profile in world space, ready for lookups and sampling.
#[derive(Clone, Debug)]
pub struct IntensityProfile {
    /// World to table axes (x', y', z'): theta = acos z', phi = atan2(y', x').
    to_table: Mat3,
    /// Table axes to world (the inverse, a transpose: both are orthogonal).
    to_world: Mat3,
    theta: Vec<f32>,
    cos_theta: Vec<f32>,
    phi: Vec<f32>,
    values: Vec<f32>,
    /// Per cell (row-major over theta cells, then phi cells): the bound b_k.
    bounds: Vec<f32>,
    cells: Distribution1D,
    /// sum_k b_k Omega_k.
    total: f32,
    /// The integral of the intensity over the sphere (exact for the bilinear table; a spot's
    /// falloff taken at each cell's middle angle, as light selection needs only proportions).
    integral: f32,
}

/// Why a table cannot be a profile.
#[derive(Debug, Clone, PartialEq)]
pub enum ProfileError {
    /// Fewer than two rows, or no column.
    TooSmall,
    /// Angles out of order or out of range, or values negative or not finite.
    Invalid(&'static str),
    /// Every value is zero (within a spot's cone).
    Dark,
}

impl std::fmt::Display for ProfileError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ProfileError::TooSmall => write!(
                f,
                "an intensity profile needs at least two polar angles and one azimuth"
            ),
            ProfileError::Invalid(what) => write!(f, "invalid intensity profile: {what}"),
            ProfileError::Dark => write!(f, "the intensity profile emits no light"),
        }
    }
}

impl IntensityProfile {
    /// Builds the profile of `table`, its values multiplied by `scale`, for a light whose local
    /// frame goes to world space by the rotation `light_to_world`; `cone` is a spot's falloff
    /// about the table's pole (it multiplies the values in `integral` and bounds the sampling
    /// weights; `eval` leaves it to the caller).
    pub fn new(
        table: &IntensityTable,
        scale: f32,
        light_to_world: Mat3,
        cone: Option<&SpotCone>,
    ) -> Result<Self, ProfileError> {
        let (nt, np) = (table.theta.len(), table.phi.len());
        if nt < 2 || np == 0 || table.values.len() != nt * np {
            return Err(ProfileError::TooSmall);
        }
        let increasing = |a: &[f32]| a.windows(2).all(|w| w[0] < w[1]);
        if !increasing(&table.theta)
            || table.theta[0] < 0.0
            || table.theta[nt - 1] > std::f32::consts::PI
        {
            return Err(ProfileError::Invalid(
                "polar angles must increase within [0, pi]",
            ));
        }
        if !increasing(&table.phi) || table.phi[0] < 0.0 || table.phi[np - 1] >= TAU {
            return Err(ProfileError::Invalid(
                "azimuths must increase within [0, 2 pi)",
            ));
        }
        if table.values.iter().any(|v| !(v.is_finite() && *v >= 0.0)) || !scale.is_finite() {
            return Err(ProfileError::Invalid(
                "values must be finite and not negative",
            ));
        }
        let values: Vec<f32> = table.values.iter().map(|v| v * scale).collect();
        let cos_theta: Vec<f32> = table.theta.iter().map(|t| t.cos()).collect();
        let falloff = |cos: f32| cone.map_or(1.0, |c| c.falloff(cos));
        let mut bounds = Vec::with_capacity((nt - 1) * np);
        let mut weights = Vec::with_capacity((nt - 1) * np);
        let mut integral = 0.0f64;
        // Per row of cells: int over [theta_i, theta_i+1] of (theta - theta_i) / dt sin theta
        // = (sin theta_i+1 - sin theta_i) / dt - cos theta_i+1.
        let moment: Vec<f32> = (0..nt - 1)
            .map(|i| {
                let (t0, t1) = (table.theta[i], table.theta[i + 1]);
                (t1.sin() - t0.sin()) / (t1 - t0) - t1.cos()
            })
            .collect();
        for i in 0..nt - 1 {
            let d_cos = cos_theta[i] - cos_theta[i + 1];
            let mid_cos = (0.5 * (table.theta[i] + table.theta[i + 1])).cos();
            for j in 0..np {
                let (j1, d_phi) = phi_cell(&table.phi, j);
                let c = [
                    values[i * np + j],
                    values[i * np + j1],
                    values[(i + 1) * np + j],
                    values[(i + 1) * np + j1],
                ];
                let omega = d_phi * d_cos;
                let b = c.iter().fold(0.0f32, |m, &x| m.max(x)) * falloff(cos_theta[i]);
                bounds.push(b);
                weights.push(b * omega);
                // Exact for the bilinear values: linear in phi, and in theta
                // int (a + (b - a)(theta - theta_i) / dt) sin theta = a d_cos + (b - a) m.
                let (a, b) = (0.5 * (c[0] + c[1]), 0.5 * (c[2] + c[3]));
                integral += f64::from((a * d_cos + (b - a) * moment[i]) * d_phi * falloff(mid_cos));
            }
        }
        let total: f32 = weights.iter().sum();
        let cells = Distribution1D::new(&weights).ok_or(ProfileError::Dark)?;
        if !(total > 0.0) {
            return Err(ProfileError::Dark);
        }
        let axes_to_world = light_to_world * table.axes.transpose();
        Ok(IntensityProfile {
            to_table: axes_to_world.transpose(),
            to_world: axes_to_world,
            theta: table.theta.clone(),
            cos_theta,
            phi: table.phi.clone(),
            values,
            bounds,
            cells,
            total,
            integral: integral as f32,
        })
    }

    /// The cell of the unit world direction `dir` (row, column) and its (theta, phi)
    /// fractions, or `None` outside the table's rows.
    #[inline]
    fn locate(&self, dir: Vec3) -> Option<(usize, usize, f32, f32)> {
        let d = self.to_table * dir;
        let theta = d.z.clamp(-1.0, 1.0).acos();
        let nt = self.theta.len();
        // A rounding margin (1e-5 rad), so that a direction exactly on the first or last row,
        // rotated, still finds it.
        if theta < self.theta[0] - 1e-5 || theta > self.theta[nt - 1] + 1e-5 {
            return None;
        }
        let i = (self.theta.partition_point(|&t| t <= theta).max(1) - 1).min(nt - 2);
        let mut phi = d.y.atan2(d.x);
        if phi < self.phi[0] {
            phi += TAU;
        }
        let j = self.phi.partition_point(|&p| p <= phi).max(1) - 1;
        let (_, d_phi) = phi_cell(&self.phi, j);
        let s = ((phi - self.phi[j]) / d_phi).clamp(0.0, 1.0);
        let t = ((theta - self.theta[i]) / (self.theta[i + 1] - self.theta[i])).clamp(0.0, 1.0);
        Some((i, j, t, s))
    }

    /// The profile's value (scaled) towards the unit world direction `dir`, bilinear in the
    /// angles; 0 outside its rows.
    #[inline]
    pub fn eval(&self, dir: Vec3) -> f32 {
        let Some((i, j, t, s)) = self.locate(dir) else {
            return 0.0;
        };
        let np = self.phi.len();
        let (j1, _) = phi_cell(&self.phi, j);
        let v = |r: usize, c: usize| self.values[r * np + c];
        let lo = v(i, j) + s * (v(i, j1) - v(i, j));
        let hi = v(i + 1, j) + s * (v(i + 1, j1) - v(i + 1, j));
        lo + t * (hi - lo)
    }

    /// A unit world direction for the uniform numbers `u` and its solid-angle density (module
    /// documentation).
    #[inline]
    pub fn sample(&self, u: Vec2) -> (Vec3, f32) {
        let (k, _, ux) = self.cells.sample(u.x);
        let np = self.phi.len();
        let (i, j) = (k / np, k % np);
        let (_, d_phi) = phi_cell(&self.phi, j);
        let phi = self.phi[j] + ux * d_phi;
        let cos = self.cos_theta[i] - u.y * (self.cos_theta[i] - self.cos_theta[i + 1]);
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let local = Vec3::new(sin * phi.cos(), sin * phi.sin(), cos);
        (
            (self.to_world * local).normalize(),
            self.bounds[k] / self.total,
        )
    }

    /// The density with which [`IntensityProfile::sample`] draws the unit world direction
    /// `dir`, per unit solid angle.
    #[inline]
    pub fn pdf(&self, dir: Vec3) -> f32 {
        self.locate(dir).map_or(0.0, |(i, j, _, _)| {
            self.bounds[i * self.phi.len() + j] / self.total
        })
    }

    /// The integral of the values (times a spot's falloff) over the sphere, sr: the power of
    /// the light per unit of its intensity's luminance.
    pub fn integral(&self) -> f32 {
        self.integral
    }
}

/// The column after `j` (wrapping) and the azimuth span of cell `j`: to the next node, the last
/// cell wrapping round to the first node; a single column spans the whole turn.
#[inline]
fn phi_cell(phi: &[f32], j: usize) -> (usize, f32) {
    let n = phi.len();
    if j + 1 < n {
        (j + 1, phi[j + 1] - phi[j])
    } else {
        (0, phi[0] + TAU - phi[j])
    }
}

/// The table of an equirectangular image's values laid out as Mitsuba's `envmap` in the light's
/// frame (rows from the light's +y pole, row `y` at theta = pi y / (H - 1); column `x` at
/// u = (x + 1/2) / W with u = atan2(x, -z) / (2 pi)): `values` row-major, one per pixel.
pub fn envmap_table(width: usize, height: usize, values: Vec<f32>) -> IntensityTable {
    let theta = (0..height)
        .map(|y| std::f32::consts::PI * y as f32 / (height.max(2) - 1) as f32)
        .collect();
    let phi = (0..width)
        .map(|x| TAU * (x as f32 + 0.5) / width as f32)
        .collect();
    IntensityTable {
        theta,
        phi,
        values,
        // (x', y', z') = (-z, x, y): phi = atan2(x, -z), theta = acos(y).
        axes: Mat3::from_cols(Vec3::Y, Vec3::Z, -Vec3::X),
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use pt_scene::ies::parse_ies;
    use rand::{RngExt, SeedableRng};
    use rand_pcg::Pcg64Mcg;

    /// A quadrant-symmetric file with uneven angles (5 and 22.5 degree steps, as real files
    /// have) and a light rotated away from the identity.
    const QUADRANT: &str = "IESNA:LM-63-2002\n[TEST] quadrant\nTILT=NONE\n1 -1 1.5 6 3 1 2 0 0 0\n1 1 30\n0 5 10 30 60 90\n0 22.5 90\n1000 980 900 500 100 0\n1000 950 800 400 80 10\n1000 900 700 300 50 20\n";

    /// The integral of `f` over the unit sphere by the midpoint rule on an n x 2n grid in
    /// (z, phi), equal-area cells.
    pub(crate) fn over_sphere(n: usize, f: impl Fn(Vec3) -> f32) -> f64 {
        let mut sum = 0.0f64;
        for a in 0..n {
            for b in 0..2 * n {
                let z = 1.0 - 2.0 * (a as f32 + 0.5) / n as f32;
                let phi = TAU * (b as f32 + 0.5) / (2 * n) as f32;
                let s = (1.0 - z * z).sqrt();
                sum += f64::from(f(Vec3::new(s * phi.cos(), s * phi.sin(), z)));
            }
        }
        sum * 4.0 * std::f64::consts::PI / (2 * n * n) as f64
    }

    fn rotation() -> Mat3 {
        Mat3::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 0.7)
    }

    #[test]
    fn values_at_the_files_angles_are_its_candelas() {
        let table = parse_ies(QUADRANT).unwrap();
        let rot = rotation();
        let p = IntensityProfile::new(&table, 2.0, rot, None).unwrap();
        let vertical = [0.0f32, 5.0, 10.0, 30.0, 60.0, 90.0];
        let rows = [
            [1000.0f32, 980.0, 900.0, 500.0, 100.0, 0.0],
            [1000.0, 950.0, 800.0, 400.0, 80.0, 10.0],
            [1000.0, 900.0, 700.0, 300.0, 50.0, 20.0],
        ];
        // Measured planes C = 0, 22.5, 90 and their mirror images (quadrant symmetry).
        for (h, row) in [0.0f32, 22.5, 90.0].iter().zip(rows) {
            for c in [*h, 180.0 - h, 180.0 + h, 360.0 - h] {
                for (g, cd) in vertical.iter().zip(row) {
                    let (g, c) = (g.to_radians(), c.to_radians());
                    let local = Vec3::new(g.sin() * c.cos(), g.sin() * c.sin(), g.cos());
                    let got = p.eval(rot * local);
                    // multiplier 1.5, scale 2.
                    let want = cd * 1.5 * 2.0;
                    assert!(
                        (got - want).abs() <= 1e-3 * want.max(1.0),
                        "C {c} gamma {g}: {got} vs {want}"
                    );
                }
            }
        }
        // Between angles: linear in gamma (20 degrees, halfway 10..30) and in C (45 degrees on
        // the 22.5..90 span, a third of the way).
        let at = |g: f32, c: f32| {
            let (g, c) = (g.to_radians(), c.to_radians());
            p.eval(rot * Vec3::new(g.sin() * c.cos(), g.sin() * c.sin(), g.cos()))
        };
        assert!((at(20.0, 0.0) - 0.5 * (900.0 + 500.0) * 3.0).abs() < 0.5);
        let want = (800.0 + (22.5 / 67.5) * (700.0 - 800.0)) * 3.0;
        assert!(
            (at(10.0, 45.0) - want).abs() < 0.5,
            "{} vs {want}",
            at(10.0, 45.0)
        );
        // Above the last vertical angle nothing is emitted.
        assert_eq!(at(120.0, 10.0), 0.0);
    }

    #[test]
    fn sampling_density_integrates_to_one_and_matches_pdf() {
        // The density's integral over the sphere by stratified quadrature, and sample() against
        // pdf(): a wrong cell weight or solid angle breaks one of them.
        let table = parse_ies(QUADRANT).unwrap();
        let cone = SpotCone {
            cos_cutoff: 50f32.to_radians().cos(),
            cutoff: 50f32.to_radians(),
            beam_width: 20f32.to_radians(),
        };
        for cone in [None, Some(&cone)] {
            let p = IntensityProfile::new(&table, 1.0, rotation(), cone).unwrap();
            let sum = over_sphere(400, |d| p.pdf(d));
            assert!((sum - 1.0).abs() < 5e-3, "integral of the pdf {sum}");
            let mut rng = Pcg64Mcg::seed_from_u64(7);
            for _ in 0..2000 {
                let (d, pdf) = p.sample(Vec2::new(rng.random::<f32>(), rng.random::<f32>()));
                assert!((d.length() - 1.0).abs() < 1e-4);
                assert!(
                    (pdf - p.pdf(d)).abs() <= 1e-3 * pdf,
                    "{pdf} vs {}",
                    p.pdf(d)
                );
                // The bound: intensity times falloff at most b_k = pdf * total.
                let fall = cone.map_or(1.0, |c| c.falloff(d.dot(rotation() * Vec3::Z)));
                assert!(p.eval(d) * fall <= pdf * p.total * 1.0001);
            }
        }
    }

    #[test]
    fn importance_sampled_mean_is_the_integral() {
        // E[I(d) / p(d)] is the integral of I over the sphere; against quadrature of eval().
        let table = parse_ies(QUADRANT).unwrap();
        let p = IntensityProfile::new(&table, 1.0, rotation(), None).unwrap();
        let quad = over_sphere(600, |d| p.eval(d));
        let mut rng = Pcg64Mcg::seed_from_u64(11);
        let m = 200_000;
        let (mut s, mut s2) = (0.0f64, 0.0f64);
        for _ in 0..m {
            let (d, pdf) = p.sample(Vec2::new(rng.random::<f32>(), rng.random::<f32>()));
            let w = f64::from(p.eval(d) / pdf);
            s += w;
            s2 += w * w;
        }
        let mean = s / m as f64;
        let se = ((s2 / m as f64 - mean * mean) / m as f64).sqrt();
        // Five standard errors plus the quadrature's own error (0.2%) against a 2% bias.
        assert!(
            (mean - quad).abs() < 5.0 * se + 2e-3 * quad,
            "{mean} +- {se} vs {quad}"
        );
        assert!(
            5.0 * se < 0.01 * quad,
            "too noisy to see a 2% bias: se {se}"
        );
        // The integral for light selection is exact for the table: to the quadrature's 0.2%.
        assert!(
            (f64::from(p.integral()) - quad).abs() < 2e-3 * quad,
            "{} vs {quad}",
            p.integral()
        );
    }

    #[test]
    fn an_envmap_table_is_laid_out_as_the_envmap() {
        // A 4 x 3 image: rows at theta 0, pi/2, pi from +y; column 1 at u = 3/8, the direction
        // atan2(x, -z) = 3 pi / 4 on the equator.
        let mut v = vec![0.0f32; 12];
        v[4 + 1] = 8.0;
        let p = IntensityProfile::new(&envmap_table(4, 3, v), 1.0, Mat3::IDENTITY, None).unwrap();
        let a = 0.75 * std::f32::consts::PI;
        let d = Vec3::new(a.sin(), 0.0, -a.cos());
        assert!((p.eval(d) - 8.0).abs() < 1e-4, "{}", p.eval(d));
        assert!(p.eval(Vec3::Y) < 1e-6);
    }
}
