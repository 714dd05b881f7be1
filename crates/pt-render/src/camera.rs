//! The pinhole perspective camera, with Mitsuba 3's conventions.

use pt_math::{Mat4, Ray, Vec2, Vec3};
use pt_scene::{CameraDesc, FovAxis, Projection};

/// A perspective camera producing world-space rays for film positions in pixels.
///
/// Camera space (Mitsuba): looks along +z, +y up, +x to the *left* of the image. Film position
/// (0, 0) is the top-left corner of the top-left pixel; (width, height) the bottom-right corner.
#[derive(Clone, Debug)]
pub struct Camera {
    to_world: Mat4,
    origin: Vec3,
    /// tan of half the field of view along x and y.
    tan_half: Vec2,
    inv_size: Vec2,
    near: f32,
    far: f32,
}

impl Camera {
    /// Builds the camera for a film of `width` x `height` pixels.
    pub fn new(desc: &CameraDesc, width: u32, height: u32) -> Self {
        let (w, h) = (width as f32, height as f32);
        let Projection::Perspective { fov_deg, fov_axis } = desc.projection;
        let t = (0.5 * fov_deg.to_radians()).tan();
        // Resolve the fov axis to tan(half fov) along x (Mitsuba's fov_axis semantics).
        let tan_x = match fov_axis {
            FovAxis::X => t,
            FovAxis::Y => t * w / h,
            FovAxis::Diagonal => t * w / (w * w + h * h).sqrt(),
            FovAxis::Smaller => {
                if w <= h {
                    t
                } else {
                    t * w / h
                }
            }
            FovAxis::Larger => {
                if w >= h {
                    t
                } else {
                    t * w / h
                }
            }
        };
        Camera {
            to_world: desc.to_world,
            origin: desc.to_world.transform_point3(Vec3::ZERO),
            tan_half: Vec2::new(tan_x, tan_x * h / w),
            inv_size: Vec2::new(1.0 / w, 1.0 / h),
            near: desc.near_clip,
            far: desc.far_clip,
        }
    }

    /// The primary ray through film position `film` (pixels). Near and far clip are planes
    /// perpendicular to the view axis, as in Mitsuba.
    #[inline]
    pub fn generate_ray(&self, film: Vec2) -> Ray {
        let ndc = film * self.inv_size; // [0,1]^2, y down
        let d_cam = Vec3::new(
            (1.0 - 2.0 * ndc.x) * self.tan_half.x,
            (1.0 - 2.0 * ndc.y) * self.tan_half.y,
            1.0,
        );
        let d_world = self.to_world.transform_vector3(d_cam);
        let len = d_world.length();
        // d_cam has z = 1, so the clip planes z = near/far are at t = near * |d_cam|/|d_world|
        // along the normalised world ray... scaled by the world length of d_cam.
        Ray {
            origin: self.origin,
            dir: d_world / len,
            tmin: self.near * len,
            tmax: self.far * len,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pt_scene::SourceLoc;

    fn lookat(origin: Vec3, target: Vec3, up: Vec3) -> Mat4 {
        // Mitsuba's lookat: columns (left, up, dir, origin).
        let dir = (target - origin).normalize();
        let left = up.cross(dir).normalize();
        let new_up = dir.cross(left);
        Mat4::from_cols(
            left.extend(0.0),
            new_up.extend(0.0),
            dir.extend(0.0),
            origin.extend(1.0),
        )
    }

    #[test]
    fn image_orientation_and_fov() {
        let desc = CameraDesc {
            loc: SourceLoc::default(),
            projection: Projection::Perspective {
                fov_deg: 90.0,
                fov_axis: FovAxis::X,
            },
            to_world: lookat(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y),
            near_clip: 0.01,
            far_clip: 100.0,
        };
        let cam = Camera::new(&desc, 200, 100);
        let centre = cam.generate_ray(Vec2::new(100.0, 50.0));
        assert!((centre.dir - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6);
        assert!((centre.tmin - 0.01).abs() < 1e-7);
        // Right edge of the image looks towards world +x at 45 degrees (fov 90 on x).
        let right = cam.generate_ray(Vec2::new(200.0, 50.0));
        assert!(
            (right.dir - Vec3::new(1.0, 0.0, -1.0).normalize()).length() < 1e-6,
            "{:?}",
            right.dir
        );
        // Top edge looks up, with half the tangent (aspect 2:1).
        let top = cam.generate_ray(Vec2::new(100.0, 0.0));
        assert!((top.dir - Vec3::new(0.0, 0.5, -1.0).normalize()).length() < 1e-6);
    }
}
