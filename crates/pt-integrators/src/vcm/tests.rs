use super::mis::*;
use super::VcmSettings;
use std::f32::consts::PI;

/// A path of `k` segments from a light vertex x_0 to the camera x_k with arbitrary
/// geometry and densities (see `mis_weights_are_the_power_heuristic_over_all_strategies`).
struct SyntheticPath {
    k: usize,
    /// Squared length of segment (i, i + 1).
    d2: Vec<f32>,
    /// |cos| at vertex i of segment (i, i + 1) and of segment (i - 1, i).
    cos_next: Vec<f32>,
    cos_prev: Vec<f32>,
    /// At interior vertex i: the BSDF's solid-angle density of the direction to x_{i+1}
    /// coming from x_{i-1} (the light's side sampling), and of the direction to x_{i-1}
    /// coming from x_{i+1} (the camera's side).
    p_to_camera: Vec<f32>,
    p_to_light: Vec<f32>,
    pmf: f32,
    p_pos: f32,
    /// Emission's direction density towards x_1, light sampling's density of x_0 seen
    /// from x_1 (solid angle).
    p_dir: f32,
    p_direct: f32,
    /// The camera's solid-angle density of the direction to x_{k-1} (per pixel sample).
    p_cam: f32,
    n: f32,
    eta: f32,
}

impl SyntheticPath {
    fn random(k: usize, seed: u64) -> Self {
        let mut state = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let mut u = move |lo: f32, hi: f32| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            lo + (hi - lo) * ((state >> 40) as f32 / (1u64 << 24) as f32)
        };
        let mut v = |m: usize, lo: f32, hi: f32| (0..m).map(|_| u(lo, hi)).collect::<Vec<_>>();
        SyntheticPath {
            k,
            d2: v(k, 0.05, 4.0),
            cos_next: v(k + 1, 0.05, 1.0),
            cos_prev: v(k + 1, 0.05, 1.0),
            p_to_camera: v(k + 1, 0.02, 3.0),
            p_to_light: v(k + 1, 0.02, 3.0),
            pmf: u(0.2, 1.0),
            p_pos: u(0.1, 2.0),
            p_dir: u(0.05, 1.0),
            p_direct: u(0.1, 5.0),
            p_cam: u(0.5, 50.0),
            n: 1000.0,
            eta: u(0.01, 30.0),
        }
    }

    /// The explicit power-heuristic weights, by pbrt-v4's definition: every strategy's
    /// density of the whole path (with its sample count), squared, over their sum.
    /// Returns (connection weights by s = 0..=k, merging weights by vertex 1..k-1).
    fn explicit(&self, connections: bool, merging: bool) -> (Vec<f64>, Vec<f64>) {
        let k = self.k;
        let mut pl = vec![0.0f64; k];
        pl[0] = f64::from(self.pmf * self.p_pos);
        pl[1] = f64::from(self.p_dir * self.cos_prev[1] / self.d2[0]);
        for i in 1..k - 1 {
            pl[i + 1] = f64::from(self.p_to_camera[i] * self.cos_prev[i + 1] / self.d2[i]);
        }
        let mut pe = vec![0.0f64; k];
        pe[k - 1] = f64::from(self.p_cam * self.cos_next[k - 1] / self.d2[k - 1]);
        for i in (1..k).rev() {
            pe[i - 1] = f64::from(self.p_to_light[i] * self.cos_next[i - 1] / self.d2[i - 1]);
        }
        let direct0 = f64::from(self.pmf * self.p_direct * self.cos_next[0] / self.d2[0]);
        let prod = |v: &[f64]| v.iter().product::<f64>();
        let n = f64::from(self.n);
        let mut conn = vec![0.0f64; k + 1];
        conn[0] = prod(&pe);
        if connections {
            conn[1] = direct0 * prod(&pe[1..]);
            for s in 2..k {
                conn[s] = prod(&pl[..s]) * prod(&pe[s..]);
            }
            conn[k] = n * prod(&pl);
        }
        let mut merge = vec![0.0f64; k];
        if merging {
            for i in 1..k {
                merge[i] = f64::from(self.eta) * prod(&pl[..=i]) * prod(&pe[i..]);
            }
        }
        let total: f64 = conn.iter().chain(&merge).map(|p| p * p).sum();
        (
            conn.iter().map(|p| p * p / total).collect(),
            merge.iter().map(|p| p * p / total).collect(),
        )
    }

    /// The light subpath's partial sums at x_i (i >= 1), as the integrator carries them.
    fn light_mis(&self, i: usize, f: &Factors) -> SubpathMis {
        let direct = self.pmf * self.p_direct * self.cos_next[0] / self.d2[0];
        let emit = self.pmf * self.p_pos * self.p_dir;
        let mut m = SubpathMis::light(direct, emit, self.cos_next[0], false, f);
        m.arrive(Some(self.d2[0]), self.cos_prev[1]);
        for j in 1..i {
            m.scatter(
                self.cos_next[j],
                self.p_to_camera[j],
                self.p_to_light[j],
                false,
                f,
            );
            m.arrive(Some(self.d2[j]), self.cos_prev[j + 1]);
        }
        m
    }

    /// The camera subpath's partial sums at x_i (i <= k - 1; i = 0: arrived at the light).
    fn camera_mis(&self, i: usize, f: &Factors) -> SubpathMis {
        let k = self.k;
        let mut m = SubpathMis::camera(self.n / self.p_cam);
        m.arrive(Some(self.d2[k - 1]), self.cos_next[k - 1]);
        for j in (i + 1..k).rev() {
            m.scatter(
                self.cos_prev[j],
                self.p_to_light[j],
                self.p_to_camera[j],
                false,
                f,
            );
            m.arrive(Some(self.d2[j - 1]), self.cos_next[j - 1]);
        }
        m
    }

    /// The integrator's weights for the same strategies.
    fn implemented(&self, connections: bool, merging: bool) -> (Vec<f64>, Vec<f64>) {
        let k = self.k;
        let settings = VcmSettings {
            merging,
            connections,
            ..VcmSettings::vcm()
        };
        // eta = pi r^2 N: the radius that gives this path's eta.
        let r = (self.eta / (PI * self.n)).sqrt();
        let f = Factors::new(&settings, r, self.n);
        let mut conn = vec![0.0f64; k + 1];
        let direct_a = self.pmf * self.p_direct * self.cos_next[0] / self.d2[0];
        let emit = self.pmf * self.p_pos * self.p_dir;
        conn[0] = f64::from(emission_weight(&self.camera_mis(0, &f), direct_a, emit, &f));
        if connections {
            conn[1] = f64::from(light_sample_weight(
                &self.camera_mis(1, &f),
                self.p_to_light[1],
                self.pmf * self.p_direct,
                emit,
                self.cos_prev[1],
                self.cos_next[0],
                self.p_to_camera[1],
                &f,
            ));
            for s in 2..k {
                let (l, c) = (self.light_mis(s - 1, &f), self.camera_mis(s, &f));
                conn[s] = f64::from(connection_weight(
                    &l,
                    &c,
                    self.p_to_light[s] * self.cos_next[s - 1] / self.d2[s - 1],
                    self.p_to_camera[s - 1] * self.cos_prev[s] / self.d2[s - 1],
                    self.p_to_light[s - 1],
                    self.p_to_camera[s],
                    &f,
                ));
            }
            conn[k] = f64::from(camera_weight(
                &self.light_mis(k - 1, &f),
                self.p_cam * self.cos_next[k - 1] / self.d2[k - 1] / self.n,
                self.p_to_light[k - 1],
                &f,
            ));
        }
        let mut merge = vec![0.0f64; k];
        if merging {
            for i in 1..k {
                merge[i] = f64::from(merge_weight(
                    &self.light_mis(i, &f),
                    &self.camera_mis(i, &f),
                    self.p_to_light[i],
                    self.p_to_camera[i],
                    &f,
                ));
            }
        }
        (conn, merge)
    }
}

/// Every strategy's weight, as the integrator computes it from its partial sums, is the
/// power heuristic over all strategies computed explicitly from the whole path's densities
/// (pbrt-v4's definition), and the weights of each path sum to one: for bdpt, vcm and
/// merging alone, on 200 random paths of 2 to 7 segments with densities spread over three
/// orders of magnitude. Tolerance 2e-3 absolute: f32 partial sums against f64 products.
/// A wrong factor anywhere (a cosine at the wrong end, a reverse density swapped, N
/// missing) moves weights by far more.
#[test]
fn mis_weights_are_the_power_heuristic_over_all_strategies() {
    for seed in 0..200u64 {
        let k = 2 + (seed % 6) as usize;
        let path = SyntheticPath::random(k, seed);
        for (connections, merging) in [(true, false), (true, true), (false, true)] {
            let (ce, me) = path.explicit(connections, merging);
            let (ci, mi) = path.implemented(connections, merging);
            let sum: f64 = ci.iter().chain(&mi).sum();

            assert!(
                (sum - 1.0).abs() < 2e-3,
                "k {k} seed {seed} ({connections}, {merging}): sum {sum}"
            );
            for (s, (e, i)) in ce.iter().zip(&ci).enumerate() {
                assert!((e - i).abs() < 2e-3, "k {k} seed {seed}: s {s}: {i} vs {e}");
            }
            for (v, (e, i)) in me.iter().zip(&mi).enumerate() {
                assert!(
                    (e - i).abs() < 2e-3,
                    "k {k} seed {seed}: merge at {v}: {i} vs {e}"
                );
            }
        }
    }
}
