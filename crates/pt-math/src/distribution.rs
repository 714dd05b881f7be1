//! Discrete distributions.

/// A discrete distribution over `n` items proportional to non-negative weights, sampled by
/// inverting its CDF. Used for light selection by power, the triangles of a mesh light and the
/// pixels of an environment map.
///
/// The inversion starts from a guide table (Chen and Asau 1974, "On generating random
/// variates from an empirical distribution"): `n` equal intervals of `u`, each with the item
/// its lower end falls in, from which a short scan finds `u`'s item. With as many intervals as
/// items the expected scan is below two steps whatever the weights, where a binary search
/// takes log2(n) dependent loads (an environment map's sampling was 12-14% of a render's time).
/// The item found is the one the binary search finds, bit for bit.
#[derive(Clone, Debug)]
pub struct Distribution1D {
    /// Normalised CDF: cdf[i] = sum of pmf[0..i], cdf[n] = 1.
    cdf: Vec<f32>,
    pmf: Vec<f32>,
    /// guide[k]: the item that u = k / n falls in.
    guide: Vec<u32>,
}

impl Distribution1D {
    /// Builds the distribution. Negative or non-finite weights count as 0. If every weight is 0
    /// the distribution is uniform, so that sampling still works (callers that need to know can
    /// check the weights themselves). Returns `None` for an empty list.
    pub fn new(weights: &[f32]) -> Option<Self> {
        if weights.is_empty() {
            return None;
        }
        let clean: Vec<f64> = weights
            .iter()
            .map(|&w| {
                if w.is_finite() && w > 0.0 {
                    w as f64
                } else {
                    0.0
                }
            })
            .collect();
        let total: f64 = clean.iter().sum();
        let n = weights.len();
        let pmf: Vec<f32> = if total > 0.0 {
            clean.iter().map(|w| (w / total) as f32).collect()
        } else {
            vec![1.0 / n as f32; n]
        };
        let mut cdf = Vec::with_capacity(n + 1);
        let mut acc = 0.0f64;
        cdf.push(0.0);
        for &p in &pmf {
            acc += p as f64;
            cdf.push(acc as f32);
        }
        // Make the last entry exactly 1 so that every u in [0, 1) maps to an item.
        if let Some(last) = cdf.last_mut() {
            *last = 1.0;
        }
        // One merge of the interval ends k / n (increasing) with the CDF.
        let mut guide = Vec::with_capacity(n);
        let mut i = 0;
        for k in 0..n {
            let u = k as f32 / n as f32;
            while i + 1 < n && cdf[i + 1] <= u {
                i += 1;
            }
            guide.push(i as u32);
        }
        Some(Distribution1D { cdf, pmf, guide })
    }

    /// The item `u` (in [0, 1)) falls in: the first `i` with `cdf[i + 1] > u`, at most
    /// `n - 1`. From the guide table's item for `u`'s interval, down while the item starts
    /// above `u` (only where `u * n` rounded up to the next interval), then up while it ends
    /// at or below `u`; the item found is the only one with `cdf[i] <= u < cdf[i + 1]`.
    #[inline(always)]
    fn find(&self, u: f32) -> usize {
        let n = self.pmf.len();
        let k = ((u * n as f32) as usize).min(n - 1);
        let mut i = self.guide[k] as usize;
        while i > 0 && self.cdf[i] > u {
            i -= 1;
        }
        while i + 1 < n && self.cdf[i + 1] <= u {
            i += 1;
        }
        i
    }

    /// Number of items.
    pub fn len(&self) -> usize {
        self.pmf.len()
    }

    /// Whether there are no items (never true for a constructed distribution).
    pub fn is_empty(&self) -> bool {
        self.pmf.is_empty()
    }

    /// Probability of item `i` (discrete measure).
    #[inline]
    pub fn pmf(&self, i: usize) -> f32 {
        self.pmf.get(i).copied().unwrap_or(0.0)
    }

    /// Samples an item from `u` in [0, 1). Returns the index, its probability, and `u` rescaled
    /// to [0, 1) within the chosen item's interval (so the same number can be reused).
    /// Items with probability 0 are never returned.
    #[inline(always)]
    pub fn sample(&self, u: f32) -> (usize, f32, f32) {
        // First index i with cdf[i+1] > u (a single item, as for one light, needs no search).
        let n = self.pmf.len();
        if n == 1 {
            let p = self.pmf[0];
            return (
                0,
                p,
                if p > 0.0 {
                    ((u - self.cdf[0]) / p).clamp(0.0, 1.0 - f32::EPSILON)
                } else {
                    0.0
                },
            );
        }
        let mut i = self.find(u);
        while self.pmf[i] == 0.0 && i > 0 {
            i -= 1; // u at the very top can land past zero-weight tail items.
        }
        let p = self.pmf[i];
        let u_rescaled = if p > 0.0 {
            ((u - self.cdf[i]) / p).clamp(0.0, 1.0 - f32::EPSILON)
        } else {
            0.0
        };
        (i, p, u_rescaled)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frequencies_match_pmf() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0, 4.0]).unwrap();
        assert_eq!(d.pmf(1), 0.0);
        let n = 80_000;
        let mut counts = [0usize; 4];
        for k in 0..n {
            let (i, p, ur) = d.sample((k as f32 + 0.5) / n as f32);
            assert_eq!(p, d.pmf(i));
            assert!((0.0..1.0).contains(&ur));
            counts[i] += 1;
        }
        // Stratified u: counts are exact to +-1 per item.
        assert_eq!(counts[1], 0);
        for (i, &c) in counts.iter().enumerate() {
            assert!((c as f32 - d.pmf(i) * n as f32).abs() <= 1.5, "{i}: {c}");
        }
    }

    /// The guide table's search finds the item the binary search over the CDF finds, for
    /// equal weights, weights with zeros, plateaus, one dominant item and a long tail, at random `u` and at
    /// every CDF value and interval start and their float neighbours (where rounding of `u * n`
    /// can pick the next interval).
    #[test]
    fn guided_search_equals_binary_search() {
        let mut rng = pt_stats::rng::Pcg32::new(11, 3);
        let mut rnd = move || rng.next_f32();
        let sets: Vec<Vec<f32>> = vec![
            vec![1.0],
            // Equal weights put CDF values exactly at interval starts.
            vec![1.0; 11],
            vec![2.0; 1000],
            vec![0.0, 0.0, 5.0, 0.0],
            vec![1e6, 1.0, 1.0, 0.0, 1.0],
            (0..1000)
                .map(|i| if i % 7 == 0 { 0.0 } else { rnd() })
                .collect(),
            (0..4096)
                .map(|i| if i == 1234 { 1e5 } else { rnd() * rnd() })
                .collect(),
            (0..300).map(|i| (i as f32 * 0.05).exp()).collect(),
        ];
        for w in &sets {
            let d = Distribution1D::new(w).unwrap();
            let n = d.len();
            let binary = |u: f32| d.cdf[1..].partition_point(|&c| c <= u).min(n - 1);
            let mut us: Vec<f32> = (0..20_000).map(|_| rnd()).collect();
            for &c in &d.cdf {
                for v in [c, c.next_down(), c.next_up()] {
                    if (0.0..1.0).contains(&v) {
                        us.push(v);
                    }
                }
            }
            for k in 0..n {
                let start = k as f32 / n as f32;
                us.extend([start, start.next_down().max(0.0)]);
            }
            us.push(1.0 - f32::EPSILON / 2.0);
            for u in us {
                assert_eq!(d.find(u), binary(u), "u = {u} over {n} items");
            }
        }
    }

    #[test]
    fn degenerate_weights() {
        assert!(Distribution1D::new(&[]).is_none());
        let d = Distribution1D::new(&[0.0, f32::NAN, -1.0]).unwrap();
        assert!((d.pmf(0) - 1.0 / 3.0).abs() < 1e-6);
        let d = Distribution1D::new(&[0.0, 0.0, 5.0, 0.0]).unwrap();
        for u in [0.0, 0.5, 0.999_999] {
            assert_eq!(d.sample(u).0, 2);
        }
    }
}

/// A piecewise-constant 2D distribution on \[0,1\]^2 over a `width` x `height` grid of
/// non-negative weights (row-major, row 0 at v = 0): a marginal over rows and one conditional per
/// row (pbrt-v4 `PiecewiseConstant2D`). Sampling returns a continuous point and its density per
/// unit area of \[0,1\]^2.
#[derive(Clone, Debug)]
pub struct Distribution2D {
    width: usize,
    height: usize,
    /// Conditional distributions over columns, one per row.
    rows: Vec<Distribution1D>,
    /// Marginal over rows.
    marginal: Distribution1D,
}

impl Distribution2D {
    /// Builds from `width * height` weights. Returns `None` for an empty grid or wrong length.
    pub fn new(weights: &[f32], width: usize, height: usize) -> Option<Self> {
        if width == 0 || height == 0 || weights.len() != width * height {
            return None;
        }
        let rows: Vec<Distribution1D> = weights
            .chunks(width)
            .map(Distribution1D::new)
            .collect::<Option<_>>()?;
        let row_sums: Vec<f32> = weights
            .chunks(width)
            .map(|r| {
                r.iter()
                    .map(|&w| {
                        if w.is_finite() && w > 0.0 {
                            w as f64
                        } else {
                            0.0
                        }
                    })
                    .sum::<f64>() as f32
            })
            .collect();
        let marginal = Distribution1D::new(&row_sums)?;
        Some(Distribution2D {
            width,
            height,
            rows,
            marginal,
        })
    }

    /// Samples a point in [0,1)^2 from `u`; returns it with its pdf per unit area.
    #[inline(always)]
    pub fn sample(&self, u: glam::Vec2) -> (glam::Vec2, f32) {
        let (row, p_row, v_in) = self.marginal.sample(u.y);
        let (col, p_col, u_in) = self.rows[row].sample(u.x);
        let x = (col as f32 + u_in) / self.width as f32;
        let y = (row as f32 + v_in) / self.height as f32;
        // Discrete probability of the cell times the cell count = density on the unit square.
        let pdf = p_row * p_col * (self.width * self.height) as f32;
        (
            glam::Vec2::new(x.min(1.0 - f32::EPSILON), y.min(1.0 - f32::EPSILON)),
            pdf,
        )
    }

    /// Density per unit area of \[0,1\]^2 at `p`.
    #[inline(always)]
    pub fn pdf(&self, p: glam::Vec2) -> f32 {
        let col = ((p.x * self.width as f32) as usize).min(self.width - 1);
        let row = ((p.y * self.height as f32) as usize).min(self.height - 1);
        self.marginal.pmf(row) * self.rows[row].pmf(col) * (self.width * self.height) as f32
    }
}

#[cfg(test)]
mod tests_2d {
    use super::*;

    #[test]
    fn pdf_matches_sampling_and_integrates_to_one() {
        let w = [1.0, 2.0, 0.0, 4.0, 0.5, 0.5, 3.0, 0.0, 1.0, 2.0, 2.0, 1.0];
        let d = Distribution2D::new(&w, 4, 3).unwrap();
        // The density integrates to 1 over the unit square (midpoint rule is exact for a
        // piecewise-constant function on its own grid).
        let mut total = 0.0;
        for r in 0..3 {
            for c in 0..4 {
                total += d.pdf(glam::Vec2::new(
                    (c as f32 + 0.5) / 4.0,
                    (r as f32 + 0.5) / 3.0,
                )) / 12.0;
            }
        }
        assert!((total - 1.0).abs() < 1e-5, "{total}");
        // Density is proportional to the weight: cell (col 3, row 0) has 4/17 of the mass.
        assert!((d.pdf(glam::Vec2::new(0.9, 0.1)) / 12.0 - 4.0 / 17.0).abs() < 1e-6);
        for k in 0..1000 {
            let u = glam::Vec2::new((k as f32 * 0.618_034).fract(), (k as f32 + 0.5) / 1000.0);
            let (p, pdf) = d.sample(u);
            assert!((d.pdf(p) - pdf).abs() < 1e-4 * pdf, "{p:?}");
            assert!(pdf > 0.0);
        }
    }
}
