//! Images cast by point-like lights: a spot light's `texture` and Mitsuba's `projector`.
//!
//! Both are delta-position lights whose intensity varies over directions through a texture
//! looked up at a uv computed from the direction in the light's own frame (the inverse of its
//! `to_world`, so a scaled or sheared `to_world` stretches the image as in Mitsuba 3.9.1).
//!
//! | light | uv of the direction (x, y, z) in the light's frame | value at distance d |
//! |---|---|---|
//! | spot `texture` | (1/2 + x / (2 z tan c), 1/2 + y / (2 z tan c)), c the cutoff angle | `I T(uv) falloff / d^2` |
//! | `projector` | (1/2 - x cot(f/2) / (2 z), 1/2 - a y cot(f/2) / (2 z)), f the x field of view, a = width / height of the image | `pi s E(uv) / (z^2 cos theta)` |
//!
//! For the projector, `E` is the irradiance (over pi) on the plane z = 1 of the light's frame,
//! which the image covers exactly; outside the frustum (uv outside [0, 1]^2, or z <= 0) it
//! casts nothing. With an unscaled frame z = d cos(theta), so the value is
//! `pi s E / (d^2 cos^3 theta)`: the intensity that puts the irradiance `pi s E` on the plane
//! (Mitsuba 3.9.1's `projector.cpp`).

use crate::texture::{Texture, TexturePoint};
use pt_math::{Mat3, Vec2, Vec3};
use pt_spectrum::{SampledSpectrum, SampledWavelengths};

/// The image a spot light casts through its cone.
#[derive(Clone, Debug)]
pub struct SpotTexture {
    /// The image (an emission texture).
    pub texture: Texture,
    /// World-to-light linear map (the inverse of `to_world`'s linear part).
    pub to_local: Mat3,
    /// 1 / tan(cutoff angle): the cone's edge maps to the unit square's inscribed circle.
    pub inv_tan_cutoff: f32,
}

impl SpotTexture {
    /// The texture's value for the direction `dir` (world, from the light, any length).
    #[inline]
    pub fn eval(&self, dir: Vec3, lambda: &SampledWavelengths) -> SampledSpectrum {
        let d = self.to_local * dir;
        let k = 0.5 * self.inv_tan_cutoff / d.z;
        let uv = Vec2::new(0.5 + d.x * k, 0.5 + d.y * k);
        self.texture.eval(&TexturePoint::uv(uv), lambda)
    }
}

/// Mitsuba's `projector`: a pinhole casting an image through a perspective frustum.
#[derive(Clone, Debug)]
pub struct Projector {
    /// Position, world.
    pub position: Vec3,
    /// World-to-light linear map (the inverse of `to_world`'s linear part).
    pub to_local: Mat3,
    /// The projector's axis (`to_world` applied to +z, not normalised, as Mitsuba uses it
    /// for the cosine).
    pub axis: Vec3,
    /// The projected irradiance over pi (an emission texture).
    pub irradiance: Texture,
    /// pi times `scale`.
    pub pi_scale: f32,
    /// cot(f / 2), f the field of view along the image's x axis.
    pub cot_half_x: f32,
    /// Width / height of the image (1 for textures without a resolution).
    pub aspect: f32,
}

impl Projector {
    /// The light arriving at `x` from the projector (the irradiance-like `I / d^2`), or
    /// `None` outside the frustum.
    #[inline]
    pub fn arriving(
        &self,
        x: Vec3,
        lambda: &SampledWavelengths,
    ) -> Option<(Vec3, f32, SampledSpectrum)> {
        let to = x - self.position;
        let dist = to.length();
        if !(dist > 0.0) {
            return None;
        }
        let dir = to / dist;
        let local = self.to_local * to;
        if !(local.z > 0.0) {
            return None;
        }
        let k = 0.5 * self.cot_half_x / local.z;
        let uv = Vec2::new(0.5 - local.x * k, 0.5 - self.aspect * local.y * k);
        if !(uv.cmpge(Vec2::ZERO).all() && uv.cmple(Vec2::ONE).all()) {
            return None;
        }
        let cos = self.axis.dot(dir);
        let e = self.irradiance.eval(&TexturePoint::uv(uv), lambda);
        let value = e * (self.pi_scale / (local.z * local.z * cos));
        Some((dir, dist, value))
    }

    /// A direction of the frustum (world, unit) for the uniform numbers `u`, uniform over the
    /// image on the plane z = 1 of the light's frame, and its solid-angle density: with `M`
    /// the light's linear `to_world` and `q` the plane point, the direction `M q / |M q|` has
    /// density `|M q|^3 / (|det M| A)` (the projective map's Jacobian; `cos^3 theta / A` for
    /// an unscaled frame), A the image's area on the plane.
    pub fn sample_direction(&self, u: Vec2) -> (Vec3, f32) {
        let to_world = self.to_local.inverse();
        let half_w = 1.0 / self.cot_half_x;
        let q = Vec3::new(
            (1.0 - 2.0 * u.x) * half_w,
            (1.0 - 2.0 * u.y) * half_w / self.aspect,
            1.0,
        );
        let d = to_world * q;
        let len = d.length();
        let pdf = len * len * len / (to_world.determinant().abs() * self.image_area());
        (d / len, pdf)
    }

    /// The solid-angle density with which [`Projector::sample_direction`] draws the unit
    /// direction `dir` (world): `1 / (z^3 |det M| A)`, z the direction's depth in the light's
    /// frame (so that `M q`, q its point on the plane z = 1, has length 1 / z); 0 outside
    /// the image.
    pub fn direction_pdf(&self, dir: Vec3) -> f32 {
        let local = self.to_local * dir;
        if !(local.z > 0.0) {
            return 0.0;
        }
        let k = 0.5 * self.cot_half_x / local.z;
        let uv = Vec2::new(0.5 - local.x * k, 0.5 - self.aspect * local.y * k);
        if !(uv.cmpge(Vec2::ZERO).all() && uv.cmple(Vec2::ONE).all()) {
            return 0.0;
        }
        let det = self.to_local.inverse().determinant().abs();
        1.0 / (local.z * local.z * local.z * det * self.image_area())
    }

    /// Area of the image on the plane z = 1 of the light's frame: (2 tan(f/2))^2 / aspect.
    pub fn image_area(&self) -> f32 {
        let w = 2.0 / self.cot_half_x;
        w * w / self.aspect
    }

    /// Emitted power, W (luminance of the texture's mean): the irradiance `pi s E` over the
    /// image on the plane z = 1, which every ray of the frustum crosses once.
    pub fn power(&self) -> f32 {
        let m = self.irradiance.mean_rgb();
        self.pi_scale * crate::texture::luminance(m) * self.image_area()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pt_spectrum::SampledWavelengths;

    fn lambda() -> SampledWavelengths {
        SampledWavelengths::sample_visible(0.5)
    }

    /// A projector of constant irradiance E puts exactly pi s E on every point of the plane
    /// z = 1 of its frame inside the frustum (the value times the plane's cosine), and nothing
    /// outside; the frustum's x half-width is tan(f/2) and its y half-width tan(f/2) / aspect.
    #[test]
    fn projector_irradiance_on_its_unit_plane_is_pi_scale_e() {
        let to_world = pt_math::Mat4::from_rotation_translation(
            glam::Quat::from_rotation_x(0.7) * glam::Quat::from_rotation_y(-0.3),
            Vec3::new(0.5, 2.0, -1.0),
        );
        let (tan_half, aspect) = (0.4f32, 1.6f32);
        let p = Projector {
            position: to_world.transform_point3(Vec3::ZERO),
            to_local: Mat3::from_mat4(to_world).inverse(),
            axis: to_world.transform_vector3(Vec3::Z),
            irradiance: Texture::rgb([0.25, 0.5, 1.0]),
            pi_scale: std::f32::consts::PI * 2.0,
            cot_half_x: 1.0 / tan_half,
            aspect,
        };
        let n = to_world.transform_vector3(Vec3::Z);
        for (x, y, inside) in [
            (0.0, 0.0, true),
            (0.39, 0.0, true),
            (-0.39, 0.24, true),
            (0.3, -0.24, true),
            (0.41, 0.0, false),
            (0.0, 0.26, false),
        ] {
            let world = to_world.transform_point3(Vec3::new(x, y, 1.0));
            match p.arriving(world, &lambda()) {
                Some((dir, dist, v)) => {
                    assert!(inside, "({x}, {y}) is outside the frustum");
                    assert!((dist - (world - p.position).length()).abs() < 1e-5);
                    let e = v * n.dot(dir);
                    let want = [0.25, 0.5, 1.0].map(|c| c * 2.0 * std::f32::consts::PI);
                    for k in 0..3 {
                        assert!((e.0[k] - want[k]).abs() < 1e-4 * want[k], "{e:?}");
                    }
                }
                None => assert!(!inside, "({x}, {y}) is inside the frustum"),
            }
        }
        // Behind the projector: nothing.
        assert!(p
            .arriving(
                to_world.transform_point3(Vec3::new(0.0, 0.0, -1.0)),
                &lambda()
            )
            .is_none());
        // The image area on z = 1 is (2 tan)^2 / aspect.
        assert!((p.image_area() - 0.64 / 1.6).abs() < 1e-6);
        // The density of a sampled direction is the one `direction_pdf` gives it (what the
        // bidirectional methods weigh with), and nothing is drawn outside the frustum.
        for (ux, uy) in [(0.5, 0.5), (0.1, 0.9), (0.97, 0.02), (0.3, 0.6)] {
            let (dir, pdf) = p.sample_direction(pt_math::Vec2::new(ux, uy));
            assert!((p.direction_pdf(dir) / pdf - 1.0).abs() < 1e-4, "{ux} {uy}");
        }
        assert_eq!(p.direction_pdf(-p.axis.normalize()), 0.0);
    }

    /// The image's orientation: +x of the light's frame is u = 0 (the image is seen from
    /// behind the projector, as a camera would see it), +y is v = 0; a spot's +x is u = 1.
    #[test]
    fn texture_orientation_follows_mitsuba() {
        // A 2 x 2 nearest-neighbour image: red (0, 0), green (1, 0), blue (0, 1), white (1, 1).
        let bitmap = crate::texture::Bitmap {
            lookup: crate::texture::Lookup {
                width: 2,
                height: 2,
                filter: pt_scene::BitmapFilter::Nearest,
                wrap: pt_scene::WrapMode::Clamp,
                to_uv: pt_scene::UV_IDENTITY,
            },
            texels: vec![
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
                [1.0, 1.0, 1.0],
            ],
        };
        let texture = Texture::Bitmap(std::sync::Arc::new(bitmap));
        let p = Projector {
            position: Vec3::ZERO,
            to_local: Mat3::IDENTITY,
            axis: Vec3::Z,
            irradiance: texture.clone(),
            pi_scale: 1.0,
            cot_half_x: 1.0,
            aspect: 1.0,
        };
        let at = |x: f32, y: f32| p.arriving(Vec3::new(x, y, 1.0), &lambda()).unwrap().2 .0;
        // local +x, +y -> u < 1/2, v < 1/2: texel (0, 0), red.
        assert!(at(0.5, 0.5)[0] > 0.0 && at(0.5, 0.5)[1] == 0.0);
        // local -x, +y -> texel (1, 0), green.
        assert!(at(-0.5, 0.5)[1] > 0.0 && at(-0.5, 0.5)[0] == 0.0);
        // local +x, -y -> texel (0, 1), blue.
        assert!(at(0.5, -0.5)[2] > 0.0 && at(0.5, -0.5)[0] == 0.0);
        let spot = SpotTexture {
            texture,
            to_local: Mat3::IDENTITY,
            inv_tan_cutoff: 1.0,
        };
        // A spot's +x, +y -> u > 1/2, v > 1/2: texel (1, 1), white; -x, -y: red.
        assert_eq!(spot.eval(Vec3::new(0.5, 0.5, 1.0), &lambda()).0[2], 1.0);
        let red = spot.eval(Vec3::new(-0.5, -0.5, 1.0), &lambda()).0;
        assert_eq!((red[0], red[1], red[2]), (1.0, 0.0, 0.0));
    }
}
