//! Fresnel reflectance of a smooth interface: dielectric (real index) and conductor (complex).
//!
//! Complex index sign convention, used everywhere in the project (DESIGN.md): `eta + i k` with
//! `k >= 0` absorbing (pbrt-v4 `FrComplex`, Mitsuba `fresnel_conductor`).

/// Unpolarised Fresnel reflectance of a dielectric interface (Born & Wolf, 1999, Sec. 1.5.2;
/// pbrt-v4 eq. 9.6 and `FrDielectric`). `cos_i` is the cosine between the direction and the
/// normal, signed: negative means the direction is on the inside. `eta` is the relative index
/// inside / outside. Returns 1 under total internal reflection.
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let (cos_i, eta) = if cos_i < 0.0 {
        (-cos_i, 1.0 / eta)
    } else {
        (cos_i, eta)
    };
    let cos_i = cos_i.min(1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let r = 0.5 * (r_parl * r_parl + r_perp * r_perp);
    if r.is_finite() {
        r.clamp(0.0, 1.0)
    } else {
        1.0 // eta * cos_i + cos_t = 0 only at cos_i = 0 (grazing): total reflection
    }
}

/// Refraction of `w` (pointing away from the surface) through the normal `n` with relative
/// index `eta` (inside / outside; flipped when `w` is inside). Returns the refracted direction
/// and `etap`, the index on its side over the index on `w`'s side, or `None` under total
/// internal reflection (pbrt-v4 `Refract`, Snell's law in vector form).
pub fn refract(w: pt_math::Vec3, n: pt_math::Vec3, eta: f32) -> Option<(pt_math::Vec3, f32)> {
    let mut cos_i = n.dot(w);
    let (mut eta, mut n) = (eta, n);
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let wt = -w / eta + (cos_i / eta - cos_t) * n;
    Some((wt.normalize(), eta))
}

/// A complex number, f64: the Fresnel equations of conductors and the thin film's phases.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct C64 {
    /// Real part.
    pub re: f64,
    /// Imaginary part.
    pub im: f64,
}

impl C64 {
    /// `x + 0 i`.
    pub const fn real(x: f64) -> Self {
        C64 { re: x, im: 0.0 }
    }
    pub(crate) fn add(self, o: Self) -> Self {
        C64 {
            re: self.re + o.re,
            im: self.im + o.im,
        }
    }
    pub(crate) fn sub(self, o: Self) -> Self {
        C64 {
            re: self.re - o.re,
            im: self.im - o.im,
        }
    }
    pub(crate) fn mul(self, o: Self) -> Self {
        C64 {
            re: self.re * o.re - self.im * o.im,
            im: self.re * o.im + self.im * o.re,
        }
    }
    pub(crate) fn scale(self, s: f64) -> Self {
        C64 {
            re: self.re * s,
            im: self.im * s,
        }
    }
    pub(crate) fn div(self, o: Self) -> Self {
        let d = o.norm();
        C64 {
            re: (self.re * o.re + self.im * o.im) / d,
            im: (self.im * o.re - self.re * o.im) / d,
        }
    }
    /// |z|^2.
    pub(crate) fn norm(self) -> f64 {
        self.re * self.re + self.im * self.im
    }
    /// Principal square root (branch cut on the negative real axis; `-x + 0i` maps to `+i sqrt x`).
    pub(crate) fn sqrt(self) -> Self {
        let r = self.norm().sqrt();
        let re = (0.5 * (r + self.re)).max(0.0).sqrt();
        let im = (0.5 * (r - self.re)).max(0.0).sqrt().copysign(self.im);
        C64 { re, im }
    }
    /// `e^{i theta}` times `e^{-phi}` for `z = theta + i phi`: `exp(i z)`.
    pub(crate) fn exp_i(self) -> Self {
        let m = (-self.im).exp();
        C64 {
            re: m * self.re.cos(),
            im: m * self.re.sin(),
        }
    }
    pub(crate) fn arg(self) -> f64 {
        self.im.atan2(self.re)
    }
}

/// Unpolarised Fresnel reflectance of a conductor with complex relative index `eta + i k`, for
/// a direction at `cos_i` (clamped to [0, 1]) on the outside (pbrt-v4 `FrComplex`, eqs. 9.6-9.7
/// with complex eta: `r_parl = (eta cos_i - cos_t)/(eta cos_i + cos_t)`,
/// `r_perp = (cos_i - eta cos_t)/(cos_i + eta cos_t)`, `cos_t = sqrt(1 - sin_i^2/eta^2)`,
/// `R = (|r_parl|^2 + |r_perp|^2)/2`). Computed in f64. `eta = 0, k = 1` (Mitsuba's
/// `material="none"`) gives R = 1. At normal incidence
/// `R = ((eta-1)^2 + k^2)/((eta+1)^2 + k^2)`.
pub fn fresnel_conductor(cos_i: f32, eta: f32, k: f32) -> f32 {
    let c = f64::from(cos_i.clamp(0.0, 1.0));
    let e = C64 {
        re: f64::from(eta),
        im: f64::from(k),
    };
    let sin2_i = C64::real(1.0 - c * c);
    let e2 = e.mul(e);
    if e2.norm() == 0.0 {
        return 1.0;
    }
    let cos_t = C64::real(1.0).sub(sin2_i.div(e2)).sqrt();
    let ec = e.mul(C64::real(c));
    let r_parl = ec.sub(cos_t).div(ec.add(cos_t));
    let r_perp = C64::real(c)
        .sub(e.mul(cos_t))
        .div(C64::real(c).add(e.mul(cos_t)));
    let r = 0.5 * (r_parl.norm() + r_perp.norm());
    if r.is_finite() {
        r.clamp(0.0, 1.0) as f32
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pt_math::Vec3;

    #[test]
    fn dielectric_normal_incidence_and_tir() {
        for eta in [1.33f32, 1.5, 2.4] {
            let r0 = ((eta - 1.0) / (eta + 1.0)).powi(2);
            assert!((fresnel_dielectric(1.0, eta) - r0).abs() < 1e-6);
            assert!(
                (fresnel_dielectric(-1.0, eta) - r0).abs() < 1e-6,
                "same from inside"
            );
            // Beyond the critical angle from inside: total internal reflection.
            let crit = (1.0 / eta).asin();
            assert_eq!(fresnel_dielectric(-(crit + 0.01).cos(), eta), 1.0);
            assert!(fresnel_dielectric(-(crit - 0.01).cos(), eta) < 1.0);
            assert_eq!(fresnel_dielectric(0.0, eta), 1.0);
        }
        // Brewster's angle: the p-polarised part vanishes, R = r_perp^2 / 2.
        let eta = 1.5f32;
        let tb = eta.atan();
        let ct = (1.0 - tb.sin().powi(2) / (eta * eta)).sqrt();
        let rs = ((tb.cos() - eta * ct) / (tb.cos() + eta * ct)).powi(2);
        assert!((fresnel_dielectric(tb.cos(), eta) - 0.5 * rs).abs() < 1e-6);
    }

    #[test]
    fn conductor_normal_incidence_and_limits() {
        for (n, k) in [(0.2f32, 3.4f32), (1.1, 2.6), (0.05, 4.0), (1.5, 0.0)] {
            let expect = ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
            assert!(
                (fresnel_conductor(1.0, n, k) - expect).abs() < 1e-6,
                "{n} {k}"
            );
        }
        // k = 0 reduces to the dielectric formula at every angle.
        for c in [0.05f32, 0.3, 0.7, 1.0] {
            assert!((fresnel_conductor(c, 1.5, 0.0) - fresnel_dielectric(c, 1.5)).abs() < 1e-5);
        }
        assert!((fresnel_conductor(0.4, 0.0, 1.0) - 1.0).abs() < 1e-6);
        assert!(
            (fresnel_conductor(0.0, 0.2, 3.4) - 1.0).abs() < 1e-6,
            "grazing reflects fully"
        );
    }

    #[test]
    fn refraction_obeys_snell() {
        let w = Vec3::new(0.6, 0.0, 0.8);
        let (t, etap) = refract(w, Vec3::Z, 1.5).unwrap();
        assert_eq!(etap, 1.5);
        assert!((t.x.abs() * 1.5 - 0.6).abs() < 1e-6 && t.z < 0.0 && t.x < 0.0);
        let (back, e2) = refract(t, Vec3::Z, 1.5).unwrap();
        assert!((back - w).length() < 1e-5 && (e2 - 1.0 / 1.5).abs() < 1e-6);
        assert!(refract(Vec3::new(0.9, 0.0, -(1.0f32 - 0.81).sqrt()), Vec3::Z, 1.5).is_none());
    }
}
