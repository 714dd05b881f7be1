//! Solvers of the radiosity system `B = E + R (F B)`, per RGB channel.
//!
//! `B_i` and `E_i` are radiosities (W m^-2), `R_i` the diffuse reflectance, `F` the form factors.
//! The residual of a solution `B` in channel `c` is the area-weighted L1 norm of `E + R F B - B`
//! relative to the emitted power: `sum_i A_i |E_i + R_i (F B)_i - B_i| / sum_i A_i E_i`, i.e. the
//! fraction of the emitted power not yet accounted for. Channels that emit nothing have the exact
//! solution `B = 0` and residual 0. All solvers stop when every channel's residual is below the
//! tolerance or after `max_iterations`.
//!
//! - [`Solver::Jacobi`]: `B <- E + R F B` (all patches at once, in parallel): iteration `k` holds
//!   exactly the light of paths with up to `k` bounces.
//! - [`Solver::GaussSeidel`]: the same update in place, patch by patch (sequential), using the
//!   newest values; about half as many iterations as Jacobi for the same residual.
//! - [`Solver::Progressive`]: progressive refinement (Cohen, Chen, Wallace & Greenberg 1988):
//!   repeatedly *shoots* the unshot radiosity of the patch with the most unshot power
//!   `A_i |dB_i|`, `dB_j += R_j dB_i F_ij A_i / A_j` (reciprocity, eq. 3 of the paper). One
//!   iteration is `n` shots; its stopping quantity is the unshot power fraction
//!   `sum A_i dB_i / sum A_i E_i`, which equals the gathering residual when `F` is reciprocal.
//!   The patch with the most unshot power is found with a max segment tree (O(log n) per update).

use crate::form_factor::FormFactors;
use crate::patches::Patch;
use rayon::prelude::*;

pub use pt_scene::RadiositySolver as Solver;

/// A solution of the radiosity system.
#[derive(Clone, Debug, Default)]
pub struct Solution {
    /// Radiosity per patch and RGB channel, W m^-2 (leaving the side the patch faces).
    pub radiosity: Vec<[f32; 3]>,
    /// Iterations done (progressive: shots / patches, rounded up).
    pub iterations: u32,
    /// Shots done by progressive refinement (0 for the other solvers).
    pub shots: u64,
    /// Final gathering residual per channel (see the module doc), computed from the returned
    /// radiosity.
    pub residual: [f32; 3],
    /// The stopping quantity after each iteration (Jacobi, Gauss-Seidel: the residual of that
    /// iterate; progressive: the unshot power fraction).
    pub history: Vec<[f32; 3]>,
    /// Whether the tolerance was reached within the iteration limit.
    pub converged: bool,
}

#[allow(clippy::needless_range_loop)]
/// Emitted power per channel, `sum_i A_i E_i` (W per unit of radiance scale).
fn emitted_power(patches: &[Patch]) -> [f64; 3] {
    let mut p = [0.0f64; 3];
    for q in patches {
        for c in 0..3 {
            p[c] += q.area as f64 * q.emission[c] as f64;
        }
    }
    p
}

/// `(F B)_i`: radiosity gathered by patch `i` (its irradiance, W m^-2).
#[inline]
pub fn gather(ff: &FormFactors, b: &[[f32; 3]], i: usize) -> [f32; 3] {
    let (c, v) = ff.row(i);
    let mut h = [0.0f32; 3];
    for (&j, &f) in c.iter().zip(v) {
        let bj = b[j as usize];
        h[0] += f * bj[0];
        h[1] += f * bj[1];
        h[2] += f * bj[2];
    }
    h
}

/// The relative gathering residual of `b` per channel (see the module doc).
pub fn residual(patches: &[Patch], ff: &FormFactors, b: &[[f32; 3]]) -> [f32; 3] {
    let power = emitted_power(patches);
    let sums = (0..patches.len())
        .into_par_iter()
        .map(|i| {
            let h = gather(ff, b, i);
            let p = &patches[i];
            let mut r = [0.0f64; 3];
            for c in 0..3 {
                r[c] = p.area as f64
                    * (p.emission[c] + p.reflectance[c] * h[c] - b[i][c]).abs() as f64;
            }
            r
        })
        .reduce(|| [0.0; 3], |a, b| [a[0] + b[0], a[1] + b[1], a[2] + b[2]]);
    std::array::from_fn(|c| {
        if power[c] > 0.0 {
            (sums[c] / power[c]) as f32
        } else {
            0.0
        }
    })
}

fn below(r: &[f32; 3], tol: f32) -> bool {
    r.iter().all(|&v| v < tol)
}

/// Solves `B = E + R F B` with `solver` until the relative residual of every channel is below
/// `tolerance` or `max_iterations` iterations were done. `progress` receives the iteration
/// count and the largest residual channel.
pub fn solve(
    patches: &[Patch],
    ff: &FormFactors,
    solver: Solver,
    tolerance: f32,
    max_iterations: u32,
    progress: &(dyn Fn(u32, f32) + Sync),
) -> Solution {
    let n = patches.len();
    let mut b: Vec<[f32; 3]> = patches.iter().map(|p| p.emission).collect();
    let mut history = Vec::new();
    let mut iterations = 0;
    let mut shots = 0u64;
    let mut converged = false;
    match solver {
        Solver::Jacobi => {
            let mut next = b.clone();
            let power = emitted_power(patches);
            for _ in 0..max_iterations {
                // next = E + R F b; the residual of b is |next - b|, weighted by area.
                let sums = next
                    .par_iter_mut()
                    .enumerate()
                    .map(|(i, out)| {
                        let h = gather(ff, &b, i);
                        let p = &patches[i];
                        let mut r = [0.0f64; 3];
                        for c in 0..3 {
                            out[c] = p.emission[c] + p.reflectance[c] * h[c];
                            r[c] = p.area as f64 * (out[c] - b[i][c]).abs() as f64;
                        }
                        r
                    })
                    .reduce(|| [0.0; 3], |a, b| [a[0] + b[0], a[1] + b[1], a[2] + b[2]]);
                let r: [f32; 3] = std::array::from_fn(|c| {
                    if power[c] > 0.0 {
                        (sums[c] / power[c]) as f32
                    } else {
                        0.0
                    }
                });
                // The residual just measured belongs to b, before this update.
                if below(&r, tolerance) {
                    converged = true;
                    break;
                }
                std::mem::swap(&mut b, &mut next);
                iterations += 1;
                history.push(r);
                progress(iterations, r.iter().copied().fold(0.0, f32::max));
            }
        }
        Solver::GaussSeidel => {
            for _ in 0..max_iterations {
                let r = residual(patches, ff, &b);
                if below(&r, tolerance) {
                    converged = true;
                    break;
                }
                for i in 0..n {
                    let h = gather(ff, &b, i);
                    let p = &patches[i];
                    b[i] = std::array::from_fn(|c| p.emission[c] + p.reflectance[c] * h[c]);
                }
                iterations += 1;
                history.push(r);
                progress(iterations, r.iter().copied().fold(0.0, f32::max));
            }
        }
        Solver::Progressive => {
            // Radiosity and unshot radiosity accumulate thousands of small shots per patch: kept
            // in f64 so that rounding stays far below the tolerance (f32 drifted by 1e-5).
            let power = emitted_power(patches);
            let mut acc: Vec<[f64; 3]> =
                patches.iter().map(|p| p.emission.map(f64::from)).collect();
            let mut unshot = acc.clone();
            let key = |u: &[f64; 3], a: f32| (a as f64 * (u[0] + u[1] + u[2])) as f32;
            let mut tree = MaxTree::new(n);
            for (i, p) in patches.iter().enumerate() {
                tree.set(i, key(&unshot[i], p.area));
            }
            let unshot_fraction = |unshot: &[[f64; 3]]| -> [f32; 3] {
                let mut s = [0.0f64; 3];
                for (u, p) in unshot.iter().zip(patches) {
                    for c in 0..3 {
                        s[c] += p.area as f64 * u[c];
                    }
                }
                std::array::from_fn(|c| {
                    if power[c] > 0.0 {
                        (s[c] / power[c]) as f32
                    } else {
                        0.0
                    }
                })
            };
            'outer: while iterations < max_iterations {
                let r = unshot_fraction(&unshot);
                if below(&r, tolerance) {
                    converged = true;
                    break;
                }
                for _ in 0..n.max(1) {
                    let Some(i) = tree.argmax() else {
                        converged = true;
                        break 'outer;
                    };
                    let u = unshot[i];
                    unshot[i] = [0.0; 3];
                    tree.set(i, 0.0);
                    let ai = patches[i].area as f64;
                    let (c, v) = ff.row(i);
                    for (&j, &f) in c.iter().zip(v) {
                        let j = j as usize;
                        let q = &patches[j];
                        let w = f as f64 * ai / q.area as f64;
                        for ch in 0..3 {
                            let d = q.reflectance[ch] as f64 * u[ch] * w;
                            acc[j][ch] += d;
                            unshot[j][ch] += d;
                        }
                        tree.set(j, key(&unshot[j], q.area));
                    }
                    shots += 1;
                }
                iterations += 1;
                let r = unshot_fraction(&unshot);
                history.push(r);
                progress(iterations, r.iter().copied().fold(0.0, f32::max));
                if below(&r, tolerance) {
                    converged = true;
                    break;
                }
            }
            b = acc.iter().map(|x| x.map(|v| v as f32)).collect();
        }
    }
    let residual = residual(patches, ff, &b);
    Solution {
        radiosity: b,
        iterations,
        shots,
        residual,
        history,
        converged,
    }
}

/// A max segment tree over `n` non-negative keys: `set` and `argmax` in O(log n).
struct MaxTree {
    size: usize,
    key: Vec<f32>,
    idx: Vec<u32>,
}

impl MaxTree {
    fn new(n: usize) -> Self {
        let size = n.next_power_of_two().max(1);
        let mut idx = vec![0u32; 2 * size];
        for (i, v) in idx[size..].iter_mut().enumerate() {
            *v = i as u32;
        }
        MaxTree {
            size,
            key: vec![0.0; 2 * size],
            idx,
        }
    }

    fn set(&mut self, i: usize, k: f32) {
        let mut p = self.size + i;
        self.key[p] = k;
        while p > 1 {
            p /= 2;
            let (l, r) = (2 * p, 2 * p + 1);
            let m = if self.key[r] > self.key[l] { r } else { l };
            self.key[p] = self.key[m];
            self.idx[p] = self.idx[m];
        }
    }

    /// The index of the largest key, or `None` when every key is 0.
    fn argmax(&self) -> Option<usize> {
        (self.key[1] > 0.0).then_some(self.idx[1] as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn max_tree_finds_the_largest() {
        let mut t = MaxTree::new(5);
        assert_eq!(t.argmax(), None);
        for (i, k) in [3.0, 1.0, 7.0, 2.0, 5.0].into_iter().enumerate() {
            t.set(i, k);
        }
        assert_eq!(t.argmax(), Some(2));
        t.set(2, 0.0);
        assert_eq!(t.argmax(), Some(4));
        t.set(1, 9.0);
        assert_eq!(t.argmax(), Some(1));
    }
}
