//! prototype
use super::RgbSigmoid;
use rayon::prelude::*;

/// smoothstep
fn smoothstep(x: f64) -> f64 {
    x * x * (3.0 - 2.0 * x)
}

pub struct RgbToSpectrumTable {
    res: usize,
    scale: Vec<f32>,
    coeffs: Vec<[f32; 3]>,
}

impl RgbToSpectrumTable {
    pub fn build(res: usize) -> Self {
        let scale: Vec<f32> = (0..res)
            .map(|k| smoothstep(smoothstep(k as f64 / (res - 1) as f64)) as f32)
            .collect();
        let start = res / 5;
        let columns: Vec<Vec<[f32; 3]>> = (0..3 * res * res)
            .into_par_iter()
            .map(|col| {
                let (l, j, i) = (col / (res * res), (col / res) % res, col % res);
                let x = i as f64 / (res - 1) as f64;
                let y = j as f64 / (res - 1) as f64;
                let node = |k: usize| {
                    let b = scale[k] as f64;
                    let mut rgb = [0.0f32; 3];
                    rgb[l] = b as f32;
                    rgb[(l + 1) % 3] = (x * b) as f32;
                    rgb[(l + 2) % 3] = (y * b) as f32;
                    rgb
                };
                let mut out = vec![RgbSigmoid::constant(0.0); res];
                let first = RgbSigmoid::fit(node(start));
                out[start] = first;
                let pred = std::env::var("PRED").is_ok();
                let walk = |ks: Vec<usize>, out: &mut Vec<RgbSigmoid>| {
                    let mut prev = first;
                    let mut prev2: Option<(RgbSigmoid, f32)> = None;
                    let mut bprev = scale[start];
                    for k in ks {
                        let mut s = prev;
                        if pred {
                            if let Some((p2, b2)) = prev2 {
                                if prev.c.iter().chain(&p2.c).all(|v| v.is_finite()) {
                                    let f = (scale[k] - bprev) / (bprev - b2);
                                    s = RgbSigmoid { c: [0, 1, 2].map(|i| prev.c[i] + f * (prev.c[i] - p2.c[i])) };
                                }
                            }
                        }
                        let r = stat_fit_from2(node(k), &s, &prev);
                        prev2 = Some((prev, bprev));
                        prev = r;
                        bprev = scale[k];
                        out[k] = r;
                    }
                };
                walk((start + 1..res).collect(), &mut out);
                walk((0..start).rev().collect(), &mut out);
                out.iter().map(|s| s.c).collect()
            })
            .collect();
        let mut coeffs = vec![[0.0f32; 3]; 3 * res * res * res];
        for (col, c) in columns.iter().enumerate() {
            let (l, j, i) = (col / (res * res), (col / res) % res, col % res);
            for k in 0..res {
                coeffs[((l * res + k) * res + j) * res + i] = c[k];
            }
        }
        RgbToSpectrumTable { res, scale, coeffs }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[ignore]
    fn proto_build() {
        for res in [16usize, 32] {
            let t = std::time::Instant::now();
            let tab = RgbToSpectrumTable::build(res);
            let dt = t.elapsed().as_secs_f64();
            let nonfinite = tab.coeffs.iter().filter(|c| !c.iter().all(|v| v.is_finite())).count();
            let maxc = tab.coeffs.iter().filter(|c| c.iter().all(|v| v.is_finite())).map(|c| c.iter().fold(0.0f32, |a, v| a.max(v.abs()))).fold(0.0f32, f32::max);
            eprintln!("warm evals/entry {:.2}", WARM.swap(0, std::sync::atomic::Ordering::Relaxed) as f64 / (3 * res * res * res) as f64);
            eprintln!("evals/entry {:.2} retries {}", EVALS.swap(0, std::sync::atomic::Ordering::Relaxed) as f64 / (3 * res * res * res) as f64, RETRY.swap(0, std::sync::atomic::Ordering::Relaxed));
            eprintln!("fallbacks {} fails {}", FALLBACK.swap(0, std::sync::atomic::Ordering::Relaxed), FAILS.swap(0, std::sync::atomic::Ordering::Relaxed));
            eprintln!("res {res}: {dt:.2} s, {:.1} us/entry, nonfinite {nonfinite}, max |c| {maxc}", dt * 1e6 / tab.coeffs.len() as f64);
        }
    }
}

pub static FALLBACK: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
pub static FAILS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
pub static EVALS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
pub static GN: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);
pub static WARM: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
pub static RETRY: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
fn stat_fit_from2(rgb: [f32; 3], start: &RgbSigmoid, prev: &RgbSigmoid) -> RgbSigmoid {
    use glam::DVec3;
    use super::*;
    use std::sync::atomic::Ordering::Relaxed;
    if rgb[0] == rgb[1] && rgb[1] == rgb[2] {
        return RgbSigmoid::constant(rgb[0]);
    }
    let c0 = DVec3::new(start.c[0] as f64, start.c[1] as f64, start.c[2] as f64);
    let target = DVec3::new(rgb[0] as f64, rgb[1] as f64, rgb[2] as f64);
    if c0.is_finite() && c0.abs().max_element() <= 1e4 {
        let e0 = EVALS.load(Relaxed);
        GN.store(std::env::var("GN").is_ok(), Relaxed);
        let c = solve(target, c0, 50, 1e-9);
        GN.store(false, Relaxed);
        let s = RgbSigmoid { c: [c.x as f32, c.y as f32, c.z as f32] };
        let (back, _) = rgb_and_jacobian(DVec3::new(s.c[0] as f64, s.c[1] as f64, s.c[2] as f64));
        WARM.fetch_add(EVALS.load(Relaxed) - e0, Relaxed);
        if (back - target).abs().max_element() < 1e-6 {
            return s;
        }
    }
    RETRY.fetch_add(1, Relaxed);
    stat_fit_from(rgb, prev)
}
fn stat_fit_from(rgb: [f32; 3], start: &RgbSigmoid) -> RgbSigmoid {
    use glam::DVec3;
    use super::*;
    use std::sync::atomic::Ordering::Relaxed;
    if rgb[0] == rgb[1] && rgb[1] == rgb[2] {
        return RgbSigmoid::constant(rgb[0]);
    }
    let c0 = DVec3::new(start.c[0] as f64, start.c[1] as f64, start.c[2] as f64);
    let target = DVec3::new(rgb[0] as f64, rgb[1] as f64, rgb[2] as f64);
    if !c0.is_finite() || c0.abs().max_element() > 1e4 {
        FALLBACK.fetch_add(1, Relaxed);
        return RgbSigmoid::fit(rgb);
    }
    let c = solve(target, c0, 50, 1e-9);
    let s = RgbSigmoid { c: [c.x as f32, c.y as f32, c.z as f32] };
    let (back, _) = rgb_and_jacobian(DVec3::new(s.c[0] as f64, s.c[1] as f64, s.c[2] as f64));
    if (back - target).abs().max_element() < 1e-6 {
        s
    } else {
        FALLBACK.fetch_add(1, Relaxed);
        let f = RgbSigmoid::fit(rgb);
        let (back, _) = rgb_and_jacobian(DVec3::new(f.c[0] as f64, f.c[1] as f64, f.c[2] as f64));
        if (back - target).abs().max_element() >= 1e-6 { FAILS.fetch_add(1, Relaxed); }
        f
    }
}

#[test]
#[ignore]
fn proto_eval_cost() {
    use glam::DVec3;
    use super::*;
    let t = std::time::Instant::now();
    let mut acc = 0.0;
    for k in 0..10000 {
        let (r, _) = rgb_and_jacobian(DVec3::new(1.0, -2.0, 0.1 + k as f64 * 1e-5));
        acc += r.x;
    }
    eprintln!("eval {:.2} us {acc}", t.elapsed().as_secs_f64() * 1e6 / 10000.0);
    // iterations of a warm solve along a column
    let res = 32;
    let scale: Vec<f32> = (0..res).map(|k| smoothstep(smoothstep(k as f64 / (res - 1) as f64)) as f32).collect();
    for (x, y) in [(0.3, 0.6), (0.0, 0.5), (0.9, 0.95), (0.1, 0.1)] {
        let mut prev = RgbSigmoid::fit([scale[6], scale[6] * x as f32, scale[6] * y as f32]);
        let mut line = String::new();
        for k in 7..res {
            let b = scale[k];
            let target = DVec3::new(b as f64, (x * b as f64) as f32 as f64, (y * b as f64) as f32 as f64);
            let c0 = DVec3::new(prev.c[0] as f64, prev.c[1] as f64, prev.c[2] as f64);
            // count iterations
            let mut n = 0;
            let mut c = c0;
            let mut last = 0.0;
            let mut hist = String::new();
            for it in 1..=50 {
                c = solve(target, c0, it, 1e-9);
                let (rgb, _) = rgb_and_jacobian(c);
                last = (rgb - target).length();
                hist += &format!("{last:.0e},");
                n = it;
                if last < 1e-9 { break; }
            }
            if k % 8 == 0 { eprintln!("{hist}"); }
            prev = RgbSigmoid { c: [c.x as f32, c.y as f32, c.z as f32] };
            line += &format!(" {n}:{last:.0e}:{:.0}", c.abs().max_element());
        }
        eprintln!("({x},{y}):{line}");
    }
}

const L: usize = 2;
struct Block { t: [f64; L], w: [[f64; L]; 3] }
fn blocks() -> Vec<Block> {
    use super::*;
    let q = quadrature();
    let mut out = Vec::new();
    for chunk in q.t.chunks(L).zip(q.w.chunks(L)) {
        let mut b = Block { t: [1.0; L], w: [[0.0; L]; 3] };
        for (i, (&t, &w)) in chunk.0.iter().zip(chunk.1).enumerate() {
            b.t[i] = t;
            b.w[0][i] = w.x; b.w[1][i] = w.y; b.w[2][i] = w.z;
        }
        out.push(b);
    }
    out
}
#[inline(never)]
fn eval_soa(bl: &[Block], c: glam::DVec3) -> (glam::DVec3, glam::DMat3) {
    use glam::{DVec3, DMat3};
    let mut acc = [[0.0f64; L]; 12];
    for b in bl {
        for i in 0..L {
            let t = b.t[i];
            let x = (c.x * t + c.y) * t + c.z;
            let r = 1.0 / (1.0 + x * x).sqrt();
            let s = 0.5 + 0.5 * x * r;
            let d = 0.5 * r * r * r;
            let (d1, d0) = (d * t, d * t * t);
            for ch in 0..3 {
                let w = b.w[ch][i];
                acc[ch][i] += w * s;
                acc[3 + ch][i] += w * d0;
                acc[6 + ch][i] += w * d1;
                acc[9 + ch][i] += w * d;
            }
        }
    }
    let s = |k: usize| acc[k].iter().sum::<f64>();
    (DVec3::new(s(0), s(1), s(2)), DMat3::from_cols(DVec3::new(s(3), s(4), s(5)), DVec3::new(s(6), s(7), s(8)), DVec3::new(s(9), s(10), s(11))))
}
#[test]
#[ignore]
fn proto_soa() {
    use glam::DVec3;
    use super::*;
    let bl = blocks();
    let c = DVec3::new(1.0, -2.0, 0.1);
    let (a, ja) = rgb_and_jacobian(c);
    let (b, jb) = eval_soa(&bl, c);
    eprintln!("{:?} {:?}\n{ja} {jb}", a - b, (ja - jb).to_cols_array());
    let t = std::time::Instant::now();
    let mut acc = 0.0;
    for k in 0..10000 {
        let (r, _) = eval_soa(&bl, DVec3::new(1.0, -2.0, 0.1 + k as f64 * 1e-5));
        acc += r.x;
    }
    eprintln!("soa eval {:.2} us {acc}", t.elapsed().as_secs_f64() * 1e6 / 10000.0);
}
#[test]
#[ignore]
fn proto_sqrt() {
    let ts: Vec<f64> = (0..941).map(|k| k as f64 / 940.0).collect();
    let t0 = std::time::Instant::now();
    let mut acc = 0.0;
    for k in 0..10000 {
        let c = 0.1 + k as f64 * 1e-5;
        let mut a = [0.0f64; 4];
        for ch in ts.chunks_exact(4) {
            for i in 0..4 {
                let x = (1.0 * ch[i] - 2.0) * ch[i] + c;
                a[i] += 1.0 / (1.0 + x * x).sqrt();
            }
        }
        acc += a.iter().sum::<f64>();
    }
    eprintln!("sqrt+div only {:.2} us {acc}", t0.elapsed().as_secs_f64() * 1e6 / 10000.0);
}
struct Soa { t: Vec<f64>, w: [Vec<f64>; 3] }
fn soa() -> Soa {
    use super::*;
    let q = quadrature();
    Soa { t: q.t.clone(), w: [q.w.iter().map(|w| w.x).collect(), q.w.iter().map(|w| w.y).collect(), q.w.iter().map(|w| w.z).collect()] }
}
#[inline(never)]
fn eval_v1(q: &Soa, c: glam::DVec3) -> (glam::DVec3, glam::DMat3) {
    use glam::{DVec3, DMat3};
    let n = q.t.len();
    let (t, wr, wg, wb) = (&q.t[..n], &q.w[0][..n], &q.w[1][..n], &q.w[2][..n]);
    let mut a = [0.0f64; 12];
    for k in 0..n {
        let t = t[k];
        let x = (c.x * t + c.y) * t + c.z;
        let r = 1.0 / (1.0 + x * x).sqrt();
        let s = 0.5 + 0.5 * x * r;
        let d2 = 0.5 * r * r * r;
        let d1 = d2 * t;
        let d0 = d1 * t;
        let (wr, wg, wb) = (wr[k], wg[k], wb[k]);
        a[0] += wr * s; a[1] += wg * s; a[2] += wb * s;
        a[3] += wr * d0; a[4] += wg * d0; a[5] += wb * d0;
        a[6] += wr * d1; a[7] += wg * d1; a[8] += wb * d1;
        a[9] += wr * d2; a[10] += wg * d2; a[11] += wb * d2;
    }
    (DVec3::new(a[0], a[1], a[2]), DMat3::from_cols(DVec3::new(a[3], a[4], a[5]), DVec3::new(a[6], a[7], a[8]), DVec3::new(a[9], a[10], a[11])))
}
#[inline(never)]
fn eval_v2(q: &Soa, c: glam::DVec3) -> (glam::DVec3, glam::DMat3) {
    use glam::{DVec3, DMat3};
    let n = q.t.len() / 2 * 2;
    let mut a = [[0.0f64; 2]; 12];
    let (t, wr, wg, wb) = (&q.t[..n], &q.w[0][..n], &q.w[1][..n], &q.w[2][..n]);
    for k in (0..n).step_by(2) {
        let mut s = [0.0; 2]; let mut d0 = [0.0; 2]; let mut d1 = [0.0; 2]; let mut d2 = [0.0; 2];
        for i in 0..2 {
            let t = t[k + i];
            let x = (c.x * t + c.y) * t + c.z;
            let r = 1.0 / (1.0 + x * x).sqrt();
            s[i] = 0.5 + 0.5 * x * r;
            d2[i] = 0.5 * r * r * r;
            d1[i] = d2[i] * t;
            d0[i] = d1[i] * t;
        }
        for i in 0..2 {
            let (wr, wg, wb) = (wr[k + i], wg[k + i], wb[k + i]);
            a[0][i] += wr * s[i]; a[1][i] += wg * s[i]; a[2][i] += wb * s[i];
            a[3][i] += wr * d0[i]; a[4][i] += wg * d0[i]; a[5][i] += wb * d0[i];
            a[6][i] += wr * d1[i]; a[7][i] += wg * d1[i]; a[8][i] += wb * d1[i];
            a[9][i] += wr * d2[i]; a[10][i] += wg * d2[i]; a[11][i] += wb * d2[i];
        }
    }
    let a = a.map(|v| v[0] + v[1]);
    let (r, j) = (DVec3::new(a[0], a[1], a[2]), DMat3::from_cols(DVec3::new(a[3], a[4], a[5]), DVec3::new(a[6], a[7], a[8]), DVec3::new(a[9], a[10], a[11])));
    let _ = j; (r, j) // tail ignored in bench
}
#[test]
#[ignore]
fn proto_variants() {
    use glam::DVec3;
    use super::*;
    let q = soa();
    for name in ["orig", "v1", "v2"] {
        let t = std::time::Instant::now();
        let mut acc = 0.0;
        for k in 0..20000 {
            let c = DVec3::new(1.0, -2.0, 0.1 + k as f64 * 1e-5);
            let (r, j) = match name { "orig" => rgb_and_jacobian(c), "v1" => eval_v1(&q, c), _ => eval_v2(&q, c) };
            acc += r.x + j.x_axis.y;
        }
        eprintln!("{name} {:.2} us {acc}", t.elapsed().as_secs_f64() * 1e6 / 20000.0);
    }
}
#[inline(never)]
fn eval_v3(q: &Soa, c: glam::DVec3) -> (glam::DVec3, glam::DMat3) {
    use glam::{DVec3, DMat3};
    const N: usize = 941;
    let (t, wr, wg, wb) = (&q.t[..N], &q.w[0][..N], &q.w[1][..N], &q.w[2][..N]);
    let mut s = [0.0f64; N];
    let mut d = [0.0f64; N];
    for k in 0..N {
        let t = t[k];
        let x = (c.x * t + c.y) * t + c.z;
        let r = 1.0 / (1.0 + x * x).sqrt();
        s[k] = 0.5 + 0.5 * x * r;
        d[k] = 0.5 * r * r * r;
    }
    let mut a = [0.0f64; 12];
    for k in 0..N {
        let (t, s, d2) = (t[k], s[k], d[k]);
        let d1 = d2 * t;
        let d0 = d1 * t;
        let (wr, wg, wb) = (wr[k], wg[k], wb[k]);
        a[0] += wr * s; a[1] += wg * s; a[2] += wb * s;
        a[3] += wr * d0; a[4] += wg * d0; a[5] += wb * d0;
        a[6] += wr * d1; a[7] += wg * d1; a[8] += wb * d1;
        a[9] += wr * d2; a[10] += wg * d2; a[11] += wb * d2;
    }
    (DVec3::new(a[0], a[1], a[2]), DMat3::from_cols(DVec3::new(a[3], a[4], a[5]), DVec3::new(a[6], a[7], a[8]), DVec3::new(a[9], a[10], a[11])))
}
#[test]
#[ignore]
fn proto_variants2() {
    use glam::DVec3;
    use super::*;
    let q = soa();
    for name in ["orig", "v1", "v3"] {
        let t = std::time::Instant::now();
        let mut acc = 0.0;
        for k in 0..20000 {
            let c = DVec3::new(1.0, -2.0, 0.1 + k as f64 * 1e-5);
            let (r, j) = match name { "orig" => rgb_and_jacobian(c), "v1" => eval_v1(&q, c), _ => eval_v3(&q, c) };
            acc += r.x + j.x_axis.y + j.z_axis.z;
        }
        eprintln!("{name} {:.2} us {acc}", t.elapsed().as_secs_f64() * 1e6 / 20000.0);
    }
}
