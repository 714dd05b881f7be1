//! Form factors by hemisphere ray casting, stored sparsely, with optional reciprocity
//! enforcement.
//!
//! # Estimator
//! The patch-averaged form factor (Goral et al. 1984; Cohen & Wallace 1993, ch. 4)
//! `F_ij = 1/A_i  int_Ai int_Aj cos(t_i) cos(t_j) V(x, y) / (pi r^2) dy dx`
//! is the probability that a ray leaving a uniformly chosen point of patch `i` in a
//! cosine-distributed direction first hits patch `j` (on the side patch `j` faces). With `N` rays,
//! `F_ij ~ hits_j / N` is unbiased with standard error `sqrt(F_ij (1 - F_ij) / N)`; the row sum
//! `sum_j F_ij` is the fraction of rays that hit any patch (exactly 1 in a closed scene, where every
//! ray hits a front-facing surface). Points and directions are each jittered-stratified over
//! `m x m` cells (`m = floor(sqrt(N))`, the remaining rays unstratified) and paired by a random
//! permutation, which keeps the estimator unbiased and lowers its variance.
//!
//! The BVH is built over the patch triangles themselves (not the scene's original geometry), so
//! visibility is consistent with the discretisation. Rays start at a point offset off the patch
//! with [`pt_math::offset_ray_origin`]. A ray that hits the back of a one-sided surface is absorbed
//! (that side is black): it counts towards no patch.
//!
//! # Reciprocity
//! Exact form factors satisfy `A_i F_ij = A_j F_ji`; independent estimates of the two sides do not.
//! [`Reciprocity::Average`] replaces both by their mean, `G_ij = (A_i F_ij + A_j F_ji) / 2`
//! (reciprocity exact, row sums now noisy); [`Reciprocity::Balanced`] then rescales the symmetric
//! `G` as `D G D` (symmetric Sinkhorn-Knopp balancing, Knight 2008) so that each row sum equals
//! the ray-cast hit fraction again: reciprocity and the measured row sums both hold, which makes
//! the discrete system conserve energy.
//!
//! # Storage
//! Compressed sparse rows: `8 (n + 1) + 8 nnz` bytes (a u32 column and an f32 value per entry),
//! with `nnz <= N n` (a row has at most one entry per ray; in practice rows have fewer entries
//! because rays hit the same patch).

use crate::patches::{PatchMesh, NO_PATCH};
use pt_math::warp::{square_to_cosine_hemisphere, square_to_uniform_triangle};
use pt_math::{offset_ray_origin, Frame, Ray, Vec2};
use pt_render::accel::Accel;
use pt_render::sampler::Sampler;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

pub use pt_scene::Reciprocity;

/// Sparse form-factor matrix in compressed-sparse-row form: row `i` holds `F_ij` for the patches
/// `j` that patch `i` sees, with columns in increasing order.
#[derive(Clone, Debug, Default)]
pub struct FormFactors {
    /// Start of each row in `col` / `val`; `n + 1` entries.
    pub row_start: Vec<usize>,
    /// Column (patch index) of each entry.
    pub col: Vec<u32>,
    /// Form factor of each entry (dimensionless, in [0, 1]).
    pub val: Vec<f32>,
    /// Raw row sum of each patch: the fraction of its rays that hit a patch.
    pub hit_fraction: Vec<f32>,
    /// Rays cast per patch.
    pub rays_per_patch: u32,
    /// Iterations of the symmetric balancing ([`Reciprocity::Balanced`]), 0 otherwise.
    pub balance_iterations: u32,
}

/// Random stream index of the form-factor rays (the display uses stream indices below 2^32).
const FF_STREAM: u64 = 1 << 40;
/// Patches per parallel work item.
const CHUNK: usize = 64;

/// One parallel work item's rows: (row lengths, columns, values, hit fractions).
type ChunkRows = (Vec<u32>, Vec<u32>, Vec<f32>, Vec<f32>);

struct Scratch {
    perm: Vec<u32>,
    hits: Vec<u32>,
}

impl FormFactors {
    /// Number of patches (rows).
    pub fn len(&self) -> usize {
        self.row_start.len().saturating_sub(1)
    }

    /// Whether there are no rows.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.col.len()
    }

    /// Row `i`: columns and values.
    #[inline]
    pub fn row(&self, i: usize) -> (&[u32], &[f32]) {
        let (a, b) = (self.row_start[i], self.row_start[i + 1]);
        (&self.col[a..b], &self.val[a..b])
    }

    /// `F_ij` (0 when not stored).
    pub fn get(&self, i: usize, j: usize) -> f32 {
        let (c, v) = self.row(i);
        c.binary_search(&(j as u32)).map_or(0.0, |k| v[k])
    }

    /// Sum of row `i`.
    pub fn row_sum(&self, i: usize) -> f32 {
        self.row(i).1.iter().map(|&v| v as f64).sum::<f64>() as f32
    }

    /// Bytes held (capacity of all arrays).
    pub fn memory_bytes(&self) -> usize {
        self.row_start.capacity() * 8
            + self.col.capacity() * 4
            + self.val.capacity() * 4
            + self.hit_fraction.capacity() * 4
    }

    /// Estimates all form factors with `rays` rays per patch, in parallel over patches. The result
    /// depends only on the mesh, `rays` and `seed`, not on the thread count. `progress` receives
    /// the fraction done.
    pub fn estimate(
        mesh: &PatchMesh,
        accel: &Accel,
        rays: u32,
        seed: u64,
        progress: &(dyn Fn(f32) + Sync),
    ) -> FormFactors {
        let n = mesh.patches.len();
        let rays = rays.max(1);
        let chunks = n.div_ceil(CHUNK);
        let done = AtomicUsize::new(0);
        let parts: Vec<ChunkRows> = (0..chunks)
            .into_par_iter()
            .map_init(
                || Scratch {
                    perm: Vec::with_capacity(rays as usize),
                    hits: Vec::with_capacity(rays as usize),
                },
                |scratch, c| {
                    let range = c * CHUNK..((c + 1) * CHUNK).min(n);
                    let mut lens = Vec::with_capacity(range.len());
                    let mut cols = Vec::new();
                    let mut vals = Vec::new();
                    let mut fracs = Vec::with_capacity(range.len());
                    for i in range {
                        let before = cols.len();
                        let frac =
                            estimate_row(mesh, accel, i, rays, seed, scratch, &mut cols, &mut vals);
                        lens.push((cols.len() - before) as u32);
                        fracs.push(frac);
                    }
                    let d = done.fetch_add(1, Ordering::Relaxed) + 1;
                    progress(d as f32 / chunks as f32);
                    (lens, cols, vals, fracs)
                },
            )
            .collect();
        let nnz = parts.iter().map(|p| p.1.len()).sum();
        let mut ff = FormFactors {
            row_start: Vec::with_capacity(n + 1),
            col: Vec::with_capacity(nnz),
            val: Vec::with_capacity(nnz),
            hit_fraction: Vec::with_capacity(n),
            rays_per_patch: rays,
            balance_iterations: 0,
        };
        ff.row_start.push(0);
        for (lens, cols, vals, fracs) in parts {
            for l in lens {
                let last = *ff.row_start.last().unwrap_or(&0);
                ff.row_start.push(last + l as usize);
            }
            ff.col.extend_from_slice(&cols);
            ff.val.extend_from_slice(&vals);
            ff.hit_fraction.extend_from_slice(&fracs);
        }
        ff
    }

    /// The transpose of the matrix `g_ij = A_i F_ij`, as (row_start, col, val).
    #[allow(clippy::needless_range_loop)]
    fn transpose_weighted(&self, area: &[f32]) -> (Vec<usize>, Vec<u32>, Vec<f32>) {
        let n = self.len();
        let mut count = vec![0usize; n + 1];
        for &c in &self.col {
            count[c as usize + 1] += 1;
        }
        for i in 0..n {
            count[i + 1] += count[i];
        }
        let start = count.clone();
        let mut fill = count;
        let mut col = vec![0u32; self.nnz()];
        let mut val = vec![0f32; self.nnz()];
        for i in 0..n {
            let (c, v) = self.row(i);
            for (&j, &f) in c.iter().zip(v) {
                let k = fill[j as usize];
                col[k] = i as u32;
                val[k] = area[i] * f;
                fill[j as usize] += 1;
            }
        }
        (start, col, val)
    }

    /// Makes the matrix reciprocal as `mode` says (`area[i]` is patch i's area).
    #[allow(clippy::needless_range_loop)] // i indexes rows, areas and the transpose together
    pub fn enforce_reciprocity(&mut self, area: &[f32], mode: Reciprocity) {
        if mode == Reciprocity::None || self.is_empty() {
            return;
        }
        let n = self.len();
        let (ts, tc, tv) = self.transpose_weighted(area);
        // Merge row i of A F with row i of (A F)^T: G_ij = (A_i F_ij + A_j F_ji) / 2, stored as
        // G_ij / A_i. Both rows are sorted by column.
        let mut row_start = Vec::with_capacity(n + 1);
        let mut col = Vec::with_capacity(self.nnz() * 3 / 2);
        let mut val = Vec::with_capacity(self.nnz() * 3 / 2);
        row_start.push(0);
        for i in 0..n {
            let (ac, av) = self.row(i);
            let (bc, bv) = (&tc[ts[i]..ts[i + 1]], &tv[ts[i]..ts[i + 1]]);
            let (mut a, mut b) = (0, 0);
            let inv = 0.5 / area[i];
            while a < ac.len() || b < bc.len() {
                let ca = ac.get(a).copied().unwrap_or(u32::MAX);
                let cb = bc.get(b).copied().unwrap_or(u32::MAX);
                let (c, g) = if ca == cb {
                    a += 1;
                    b += 1;
                    (ca, area[i] * av[a - 1] + bv[b - 1])
                } else if ca < cb {
                    a += 1;
                    (ca, area[i] * av[a - 1])
                } else {
                    b += 1;
                    (cb, bv[b - 1])
                };
                col.push(c);
                val.push(g * inv);
            }
            row_start.push(col.len());
        }
        self.row_start = row_start;
        self.col = col;
        self.val = val;
        self.col.shrink_to_fit();
        self.val.shrink_to_fit();
        if mode == Reciprocity::Balanced {
            self.balance(area, 1e-6, 1000);
        }
    }

    /// Symmetric Sinkhorn-Knopp balancing: finds `d > 0` such that `D G D` (G_ij = A_i F_ij,
    /// symmetric) has row sums `A_i * hit_fraction_i`, by the damped fixed point
    /// `d_i <- sqrt(d_i t_i / (G d)_i)` (Knight 2008, "The Sinkhorn-Knopp algorithm: convergence and
    /// applications"), until the largest relative row-sum error is below `tol`. Rows with a zero
    /// target or no entries keep `d_i = 1`.
    fn balance(&mut self, area: &[f32], tol: f64, max_iter: u32) {
        let n = self.len();
        let target: Vec<f64> = (0..n)
            .map(|i| area[i] as f64 * self.hit_fraction[i] as f64)
            .collect();
        let mut d = vec![1.0f64; n];
        let mut s = vec![0.0f64; n];
        let mut iterations = 0;
        for it in 0..max_iter {
            iterations = it + 1;
            // s = G d
            s.par_iter_mut().enumerate().for_each(|(i, si)| {
                let (c, v) = self.row(i);
                *si = area[i] as f64
                    * c.iter()
                        .zip(v)
                        .map(|(&j, &f)| f as f64 * d[j as usize])
                        .sum::<f64>();
            });
            let mut worst = 0.0f64;
            for i in 0..n {
                if target[i] > 0.0 && s[i] > 0.0 {
                    worst = worst.max((d[i] * s[i] / target[i] - 1.0).abs());
                }
            }
            if worst < tol {
                break;
            }
            for i in 0..n {
                if target[i] > 0.0 && s[i] > 0.0 {
                    d[i] = (d[i] * target[i] / s[i]).sqrt();
                }
            }
        }
        self.balance_iterations = iterations;
        for i in 0..n {
            let (a, b) = (self.row_start[i], self.row_start[i + 1]);
            for k in a..b {
                self.val[k] = (self.val[k] as f64 * d[i] * d[self.col[k] as usize]) as f32;
            }
        }
    }

    /// Largest reciprocity violation `|A_i F_ij - A_j F_ji|` relative to `max(A_i F_ij, A_j F_ji)`
    /// over all stored entries (0 for an exactly reciprocal matrix).
    pub fn max_reciprocity_error(&self, area: &[f32]) -> f32 {
        (0..self.len())
            .into_par_iter()
            .map(|i| {
                let (c, v) = self.row(i);
                c.iter()
                    .zip(v)
                    .map(|(&j, &f)| {
                        let a = area[i] * f;
                        let b = area[j as usize] * self.get(j as usize, i);
                        (a - b).abs() / a.max(b)
                    })
                    .fold(0.0f32, f32::max)
            })
            .reduce(|| 0.0, f32::max)
    }
}

/// Casts patch `i`'s rays and appends its row (sorted by column) to `cols` / `vals`. Returns the
/// fraction of rays that hit a patch.
#[allow(clippy::too_many_arguments)]
fn estimate_row(
    mesh: &PatchMesh,
    accel: &Accel,
    i: usize,
    rays: u32,
    seed: u64,
    scratch: &mut Scratch,
    cols: &mut Vec<u32>,
    vals: &mut Vec<f32>,
) -> f32 {
    let patch = &mesh.patches[i];
    let tri = &mesh.triangles[patch.triangle as usize];
    let p = tri.v.map(|v| mesh.vertices[v as usize]);
    let frame = Frame::from_normal(patch.normal);
    let mut sampler = Sampler::new(seed, i as u64, FF_STREAM);
    let m = (rays as f32).sqrt().floor().max(1.0) as u32;
    let strat = m * m;
    // Random pairing of point strata with direction strata (Fisher-Yates, no allocation).
    scratch.perm.clear();
    scratch.perm.extend(0..strat);
    for k in (1..strat as usize).rev() {
        let r = ((sampler.next_1d() * (k + 1) as f32) as usize).min(k);
        scratch.perm.swap(k, r);
    }
    scratch.hits.clear();
    let inv_m = 1.0 / m as f32;
    let cell = |s: u32, u: Vec2| {
        Vec2::new(
            ((s % m) as f32 + u.x) * inv_m,
            ((s / m) as f32 + u.y) * inv_m,
        )
    };
    for k in 0..rays {
        let (u_pos, u_dir) = if k < strat {
            let a = sampler.next_2d();
            let b = sampler.next_2d();
            (cell(k, a), cell(scratch.perm[k as usize], b))
        } else {
            (sampler.next_2d(), sampler.next_2d())
        };
        // Clamp so that a cell's upper edge rounding to 1.0 stays inside [0, 1).
        let u_pos = u_pos.min(Vec2::splat(1.0 - f32::EPSILON));
        let u_dir = u_dir.min(Vec2::splat(1.0 - f32::EPSILON));
        let b = square_to_uniform_triangle(u_pos);
        let x = p[0] * (1.0 - b.x - b.y) + p[1] * b.x + p[2] * b.y;
        let dir = frame
            .to_world(square_to_cosine_hemisphere(u_dir))
            .normalize();
        let ray = Ray::new(offset_ray_origin(x, patch.normal), dir);
        if let Some(prim) = accel.intersect(&ray).map(|h| h.index) {
            let t = accel.original_index[prim] as usize;
            let j = mesh.patch_hit(t, dir);
            if j != NO_PATCH {
                scratch.hits.push(j);
            }
        }
    }
    scratch.hits.sort_unstable();
    let inv_n = 1.0 / rays as f32;
    let mut k = 0;
    while k < scratch.hits.len() {
        let j = scratch.hits[k];
        let mut e = k + 1;
        while e < scratch.hits.len() && scratch.hits[e] == j {
            e += 1;
        }
        cols.push(j);
        vals.push((e - k) as f32 * inv_n);
        k = e;
    }
    scratch.hits.len() as f32 * inv_n
}
