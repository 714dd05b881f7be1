//! The cameras, with Mitsuba 3's conventions: the pinhole perspective camera, the thin-lens
//! camera and the orthographic camera, and the measuring sensors `radiancemeter` and
//! `irradiancemeter`.

use crate::light::LightShape;
use pt_math::warp::{square_to_cosine_hemisphere, square_to_disk_concentric};
use pt_math::{offset_ray_origin, Frame, Mat4, Ray, Vec2, Vec3};
use pt_scene::{CameraDesc, FovAxis, Projection};
use std::sync::Arc;

/// A camera producing world-space rays for film positions in pixels.
///
/// Camera space (Mitsuba): looks along +z, +y up, +x to the *left* of the image. Film position
/// (0, 0) is the top-left corner of the top-left pixel; (width, height) the bottom-right corner.
#[derive(Clone, Debug)]
pub struct Camera {
    /// Where the scene defines the sensor (for errors about it).
    loc: pt_scene::SourceLoc,
    to_world: Mat4,
    /// The inverse of `to_world`.
    to_camera: Mat4,
    origin: Vec3,
    kind: Kind,
    /// Perspective: tan of half the field of view along x and y. Orthographic: the half-extent
    /// of the film in camera space (1 and 1 / aspect).
    tan_half: Vec2,
    /// 1 / the whole film's size in pixels.
    inv_size: Vec2,
    /// Added to every film position (pixels) before projecting: the principal point offset in
    /// pixels (Mitsuba: the content moves by -offset x size, so the ray through a pixel is the
    /// centred camera's ray through the pixel + offset x size).
    film_offset: Vec2,
    /// The film's pixel at the image's top-left corner (a crop window's offset).
    crop_offset: [u32; 2],
    /// The image's size in pixels (a crop window's, or the whole film's).
    image_size: Vec2,
    near: f32,
    far: f32,
    /// The irradiancemeter's shape, or the distant sensor's target shape (attached by the
    /// scene, [`Camera::attach_surface`]).
    surface: Option<Arc<LightShape>>,
    /// Where a distant sensor's rays aim, and the scene's bounding sphere (centre, radius)
    /// they start outside of ([`Camera::aim`]).
    aim: Option<(Aim, Vec3, f32)>,
    /// A batch's sensors, left to right, and the width in pixels of each one's strip of the
    /// film ([`Camera::set_batch`]).
    batch: Option<(Arc<[Camera]>, u32)>,
}

/// Where a distant sensor's rays aim (world space).
#[derive(Clone, Copy, Debug)]
enum Aim {
    /// Through one point.
    Point(Vec3),
    /// Through points uniform on a disk perpendicular to the direction.
    Disk { centre: Vec3, radius: f32 },
    /// Through points uniform by area on the attached surface.
    Surface,
}

/// What a camera's rays look like.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Pinhole,
    /// Aperture radius and focus distance (camera space units: to_world has no scale).
    ThinLens {
        radius: f32,
        focus: f32,
    },
    Orthographic,
    /// One ray, camera +z from the origin (Mitsuba's `radiancemeter`).
    Radiancemeter,
    /// Rays from points on a shape, cosine-distributed about its normal (Mitsuba's
    /// `irradiancemeter`).
    Irradiancemeter,
    /// Parallel rays along camera +z aimed at a target (Mitsuba's `distant`).
    Distant,
    /// Other cameras side by side, each on its strip of the film (Mitsuba's `batch`).
    Batch,
}

/// tan(half fov) along x for a `fov_deg` spanning `fov_axis` of a `w` x `h` film (Mitsuba's
/// fov_axis semantics).
pub(crate) fn tan_half_x(fov_deg: f32, fov_axis: FovAxis, w: f32, h: f32) -> f32 {
    let t = (0.5 * fov_deg.to_radians()).tan();
    match fov_axis {
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
    }
}

impl Camera {
    /// Builds the camera for a film of `width` x `height` pixels. A thin lens of aperture 0 is
    /// the pinhole camera (the same rays, bit for bit, and no lens sample drawn).
    pub fn new(desc: &CameraDesc, width: u32, height: u32) -> Self {
        let (w, h) = (width as f32, height as f32);
        let (kind, tan_x) = match desc.projection {
            Projection::Perspective { fov_deg, fov_axis } => {
                (Kind::Pinhole, tan_half_x(fov_deg, fov_axis, w, h))
            }
            Projection::ThinLens {
                fov_deg,
                fov_axis,
                aperture_radius,
                focus_distance,
            } => {
                let kind = if aperture_radius > 0.0 {
                    Kind::ThinLens {
                        radius: aperture_radius,
                        focus: focus_distance,
                    }
                } else {
                    Kind::Pinhole
                };
                (kind, tan_half_x(fov_deg, fov_axis, w, h))
            }
            Projection::Orthographic => (Kind::Orthographic, 1.0),
            Projection::Radiancemeter => (Kind::Radiancemeter, 1.0),
            Projection::Irradiancemeter { .. } => (Kind::Irradiancemeter, 1.0),
            Projection::Distant { .. } => (Kind::Distant, 1.0),
            Projection::Batch => (Kind::Batch, 1.0),
        };
        Camera {
            loc: desc.loc.clone(),
            to_world: desc.to_world,
            to_camera: desc.to_world.inverse(),
            origin: desc.to_world.transform_point3(Vec3::ZERO),
            kind,
            tan_half: Vec2::new(tan_x, tan_x * h / w),
            inv_size: Vec2::new(1.0 / w, 1.0 / h),
            film_offset: Vec2::from(desc.principal_point_offset) * Vec2::new(w, h),
            crop_offset: [0, 0],
            image_size: Vec2::new(w, h),
            near: desc.near_clip,
            far: desc.far_clip,
            surface: None,
            aim: None,
            batch: None,
        }
    }

    /// Gives a batch its sensors (left to right; each already built for its strip of the
    /// film, `strip` pixels wide and the film's height).
    pub fn set_batch(&mut self, cameras: Vec<Camera>, strip: u32) {
        self.batch = Some((cameras.into(), strip.max(1)));
    }

    /// For a batch, the sensor whose strip holds the film column `x` (columns left and right of
    /// the film go to the first and last) and `x` within its strip.
    #[inline(always)]
    fn batch_member(&self, x: i32) -> Option<(&Camera, i32)> {
        let (cameras, strip) = self.batch.as_ref()?;
        let k = x
            .div_euclid(*strip as i32)
            .clamp(0, cameras.len() as i32 - 1);
        Some((&cameras[k as usize], x - k * *strip as i32))
    }

    /// Gives an irradiancemeter the shape it measures, or a distant sensor the shape it aims at
    /// (sampled by area, as a light is).
    pub fn attach_surface(&mut self, shape: LightShape) {
        self.surface = Some(Arc::new(shape));
    }

    /// Gives a distant sensor its target and the scene's bounding sphere (`centre`, `radius`):
    /// its rays start outside the sphere, so that they meet every surface along their line.
    pub fn aim(&mut self, target: pt_scene::DistantTarget, centre: Vec3, radius: f32) {
        let aim = match target {
            pt_scene::DistantTarget::Point(p) => Aim::Point(p),
            pt_scene::DistantTarget::BoundingDisk => Aim::Disk { centre, radius },
            pt_scene::DistantTarget::Shape => Aim::Surface,
        };
        self.aim = Some((aim, centre, radius));
    }

    /// The camera for `film`: projecting onto the whole film; [`Camera::pixel_ray`] places the
    /// image's pixels in it through the crop window.
    pub fn for_film(desc: &CameraDesc, film: &pt_scene::FilmDesc) -> Self {
        let [w, h] = film.film_size();
        let mut camera = Camera::new(desc, w, h);
        camera.crop_offset = film.crop_offset();
        camera.image_size = Vec2::new(film.width as f32, film.height as f32);
        camera
    }

    /// The primary ray for the image's pixel (x, y) at `offset` (pixels) from its centre: the
    /// film position is computed from the pixel's place in the whole film, in the same
    /// operations for any crop window, so that a cropped render traces the whole film's rays
    /// bit for bit. `u_lens` as in [`Camera::generate_ray`]. Pixels outside the image
    /// (negative or beyond its size: the border a splatting film samples with
    /// `sample_border`) continue the film's grid.
    #[inline(always)]
    pub fn pixel_ray(&self, x: i32, y: i32, offset: Vec2, u_lens: Vec2) -> Ray {
        let (camera, x) = self.batch_member(x).unwrap_or((self, x));
        camera.own_pixel_ray(x, y, offset, u_lens)
    }

    /// [`Camera::pixel_ray`] of this camera itself (a batch's member, or a camera that is no
    /// batch). A batch's members are never batches themselves (the loader refuses them), so
    /// the batch is resolved once, without recursion: a recursive function is not inlined
    /// into the render loop, and this runs once per sample.
    #[inline(always)]
    fn own_pixel_ray(&self, x: i32, y: i32, offset: Vec2, u_lens: Vec2) -> Ray {
        let centre = Vec2::new(
            (i64::from(x) + i64::from(self.crop_offset[0])) as f32 + 0.5,
            (i64::from(y) + i64::from(self.crop_offset[1])) as f32 + 0.5,
        );
        self.own_ray(centre + offset, u_lens)
    }

    /// Whether [`Camera::generate_ray`] uses its lens sample (a thin lens with an aperture):
    /// the caller draws one only then, so that pinhole images keep their random numbers.
    #[inline]
    pub fn needs_lens_sample(&self) -> bool {
        matches!(self.kind, Kind::ThinLens { .. })
            || self
                .batch
                .as_ref()
                .is_some_and(|(cameras, _)| cameras.iter().any(Camera::needs_lens_sample))
    }

    /// The camera ray of a sample of the image's pixel (x, y) at `offset` (pixels) from its
    /// centre ([`Camera::pixel_ray`]), drawing from `next_2d` the numbers the camera needs
    /// beyond the film position: a thin lens's aperture point, or an irradiancemeter's point
    /// and direction (which ignore the film position, as Mitsuba's do); nothing for the
    /// others, whose images keep their random numbers. Always inlined: it runs once per
    /// sample, in the render loop compiled for the processor's instruction sets.
    #[inline(always)]
    pub fn sample_ray(
        &self,
        x: i32,
        y: i32,
        offset: Vec2,
        mut next_2d: impl FnMut() -> Vec2,
    ) -> Ray {
        // A batch's member samples its own rays (see `own_pixel_ray`).
        let (camera, x) = self.batch_member(x).unwrap_or((self, x));
        match camera.kind {
            Kind::ThinLens { .. } => camera.own_pixel_ray(x, y, offset, next_2d()),
            Kind::Irradiancemeter => {
                let u_point = next_2d();
                camera.surface_ray(u_point, next_2d())
            }
            Kind::Distant => match camera.aim {
                Some((Aim::Point(_), ..)) | None => camera.distant_ray(Vec2::splat(0.5)),
                Some(_) => camera.distant_ray(next_2d()),
            },
            _ => camera.own_pixel_ray(x, y, offset, Vec2::splat(0.5)),
        }
    }

    /// An irradiancemeter's ray (Mitsuba's `irradiancemeter::sample_ray`): from a point
    /// uniform by area on its shape (`u_point`: x picks a mesh's triangle and is reused
    /// within it) in a cosine-distributed direction about the point's front normal (`u_dir`).
    /// Each such ray's radiance counts [`Camera::ray_weight`] = pi times, so that the mean is
    /// the area-averaged irradiance (pi times the mean of L over the cosine density). The
    /// origin is moved off the surface along the normal.
    fn surface_ray(&self, u_point: Vec2, u_dir: Vec2) -> Ray {
        let (p, n) = self.surface_point(u_point);
        let dir = Frame::from_normal(n).to_world(square_to_cosine_hemisphere(u_dir));
        Ray {
            origin: offset_ray_origin(p, n),
            dir,
            tmin: 0.0,
            tmax: f32::INFINITY,
        }
    }

    /// A point uniform by area on the attached surface and its front normal (`u`: x picks a
    /// mesh's triangle and is reused within it).
    fn surface_point(&self, u: Vec2) -> (Vec3, Vec3) {
        let surface = self.surface.as_ref().expect("the sensor has its shape");
        let (u_sel, u) = match &**surface {
            LightShape::Mesh { distr, .. } => {
                let (_, _, reused) = distr.sample(u.x);
                (u.x, Vec2::new(reused, u.y))
            }
            _ => (0.0, u),
        };
        let (p, n, _) = surface.sample_point(u_sel, u);
        (p, n)
    }

    /// A distant sensor's ray (Mitsuba's `distant`): along camera +z through a point of its
    /// target (`u` picks it on a disk or shape), starting outside the scene's bounding sphere
    /// (back along the direction by the target point's distance from the centre plus the
    /// radius).
    fn distant_ray(&self, u: Vec2) -> Ray {
        let dir = self.to_world.transform_vector3(Vec3::Z).normalize();
        let (aim, centre, radius) = self.aim.expect("a distant sensor has its target");
        let through = match aim {
            Aim::Point(p) => p,
            Aim::Disk { centre, radius } => {
                let d = square_to_disk_concentric(u) * radius;
                centre + Frame::from_normal(dir).to_world(Vec3::new(d.x, d.y, 0.0))
            }
            Aim::Surface => self.surface_point(u).0,
        };
        let back = (through - centre).length() + radius;
        Ray {
            origin: through - dir * back,
            dir,
            tmin: 0.0,
            tmax: f32::INFINITY,
        }
    }

    /// The factor every camera ray's radiance is counted with: pi for an irradiancemeter
    /// (its cosine-weighted directions measure irradiance), 1 for the others.
    #[inline]
    pub fn ray_weight(&self) -> f32 {
        if self.kind == Kind::Irradiancemeter {
            std::f32::consts::PI
        } else {
            1.0
        }
    }

    /// The primary ray through film position `film` (pixels of the whole film: (0, 0) its
    /// top-left corner); `u_lens` in [0, 1)^2 picks the
    /// point on a thin lens's aperture (unused by the other cameras). Near and far clip are
    /// planes perpendicular to the view axis, as in Mitsuba.
    #[inline]
    pub fn generate_ray(&self, film: Vec2, u_lens: Vec2) -> Ray {
        if let Some((member, x)) = self.batch_member(film.x.floor() as i32) {
            let local = Vec2::new(film.x - (film.x.floor() - x as f32), film.y);
            return member.own_ray(local, u_lens);
        }
        self.own_ray(film, u_lens)
    }

    /// [`Camera::generate_ray`] of this camera itself (see `own_pixel_ray`).
    #[inline(always)]
    fn own_ray(&self, film: Vec2, u_lens: Vec2) -> Ray {
        // [0,1]^2 on the film, y down.
        let ndc = (film + self.film_offset) * self.inv_size;
        // The film point in camera space: at z = 1 for the perspective cameras (the direction
        // of the pinhole ray), at z = 0 for the orthographic one (the ray's origin).
        let x = (1.0 - 2.0 * ndc.x) * self.tan_half.x;
        let y = (1.0 - 2.0 * ndc.y) * self.tan_half.y;
        match self.kind {
            Kind::Pinhole => {
                let d_world = self.to_world.transform_vector3(Vec3::new(x, y, 1.0));
                let len = d_world.length();
                // d_cam has z = 1, so the clip planes z = near / far are at t = near |d_world|
                // along the normalised world ray.
                Ray {
                    origin: self.origin,
                    dir: d_world / len,
                    tmin: self.near * len,
                    tmax: self.far * len,
                }
            }
            Kind::ThinLens { radius, focus } => {
                // The pinhole ray through this film point meets the plane z = focus at
                // `focus * (x, y, 1)`; every ray from the aperture disk goes through that point
                // (Kolb et al. 1995; pbrt-v4 Sec. 5.2.3).
                let a = square_to_disk_concentric(u_lens) * radius;
                let lens = Vec3::new(a.x, a.y, 0.0);
                let d_cam = Vec3::new(x, y, 1.0) * focus - lens;
                let d_world = self.to_world.transform_vector3(d_cam);
                let len = d_world.length();
                // t per unit of camera z along the normalised ray: |d_world| / d_cam.z.
                let per_z = len / d_cam.z;
                Ray {
                    origin: self.to_world.transform_point3(lens),
                    dir: d_world / len,
                    tmin: self.near * per_z,
                    tmax: self.far * per_z,
                }
            }
            Kind::Orthographic => {
                let d_world = self.to_world.transform_vector3(Vec3::Z);
                let len = d_world.length();
                Ray {
                    origin: self.to_world.transform_point3(Vec3::new(x, y, 0.0)),
                    dir: d_world / len,
                    tmin: self.near * len,
                    tmax: self.far * len,
                }
            }
            // Its rays come from the shape ([`Camera::sample_ray`]); the film position alone
            // (the film's centre) gives one of them.
            Kind::Irradiancemeter => self.surface_ray(Vec2::splat(0.5), Vec2::splat(0.5)),
            Kind::Distant => self.distant_ray(Vec2::splat(0.5)),
            // Without its sensors (not given yet): the view axis.
            Kind::Batch => Ray::new(self.origin, self.to_world.transform_vector3(Vec3::Z)),
            // The same ray for every film point (Mitsuba's radiancemeter ignores the film
            // sample); no clip planes.
            Kind::Radiancemeter => Ray {
                origin: self.origin,
                dir: self.to_world.transform_vector3(Vec3::Z).normalize(),
                tmin: 0.0,
                tmax: f32::INFINITY,
            },
        }
    }
}

/// A point of the scene connected to the camera (a light path's vertex seen by the camera).
#[derive(Clone, Copy, Debug)]
pub struct CameraConnection {
    /// The point on the camera the connection reaches (the pinhole, a point of the lens, or
    /// the orthographic film's point), world space.
    pub camera_point: Vec3,
    /// Unit direction from the scene point towards `camera_point`, world space.
    pub dir: Vec3,
    /// Distance from the scene point to `camera_point`.
    pub dist: f32,
    /// Where the connection lands on the image: pixels from the image's top-left corner (a
    /// crop window's own), inside the image.
    pub film: Vec2,
    /// The camera's importance over the density of the camera point, per unit area at the
    /// scene point: a vertex with throughput `beta` (radiance-like measure, per unit area)
    /// whose BSDF sends `f |cos|` towards the camera adds `beta f |cos| weight` to the
    /// measurement `integral of W_e L` over the whole film, whose importance integrates to 1.
    /// Pinhole: `1 / (A cos^3 theta d^2)`, A the film's area on the plane z = 1 of camera
    /// space; thin lens: the same for the ray from the sampled lens point (the lens density
    /// cancels the importance's 1 / (pi r^2)); orthographic: `1 / A`, A the film's area in the
    /// world (a delta direction: no distance falloff).
    pub weight: f32,
}

impl Camera {
    /// The camera's side of a connection from the scene point `p` (world space) to the
    /// camera (pbrt-v4's `SampleWi` of its cameras; Veach 1997, ch. 10): `None` when `p` is
    /// behind the camera, outside the near/far clip range (camera-space depth, as Mitsuba's
    /// `sample_direction` tests it) or projects outside the image. `u_lens` picks the thin
    /// lens's point (unused by the other cameras). The film position is the inverse of
    /// [`Camera::generate_ray`]: the camera ray through it passes through `p`.
    #[inline(always)]
    pub fn connect(&self, p: Vec3, u_lens: Vec2) -> Option<CameraConnection> {
        if matches!(
            self.kind,
            Kind::Radiancemeter | Kind::Irradiancemeter | Kind::Distant
        ) {
            // One ray, or rays from a surface whose importance pt does not evaluate: light paths
            // do not connect to them (the methods that need it refuse these sensors).
            return None;
        }
        let local = self.to_camera.transform_point3(p);
        if !(local.z >= self.near && local.z <= self.far) {
            return None;
        }
        let area = 4.0 * self.tan_half.x * self.tan_half.y;
        // The point's place on the plane z = 1 (perspective) or z = 0 (orthographic) of
        // camera space, the camera's point, and the importance weight.
        let (plane, camera_point, cam_dir) = match self.kind {
            Kind::Pinhole => (
                Vec2::new(local.x / local.z, local.y / local.z),
                self.origin,
                local,
            ),
            Kind::ThinLens { radius, focus } => {
                let a = square_to_disk_concentric(u_lens) * radius;
                let lens = Vec3::new(a.x, a.y, 0.0);
                let d = local - lens;
                // Where the line from the lens point through p meets the plane of focus, over
                // the focus distance: the pinhole ray's film-plane point.
                let q = (lens.truncate() + d.truncate() * (focus / d.z)) / focus;
                (q, self.to_world.transform_point3(lens), d)
            }
            Kind::Orthographic
            | Kind::Radiancemeter
            | Kind::Irradiancemeter
            | Kind::Distant
            | Kind::Batch => (
                Vec2::new(local.x, local.y),
                self.to_world
                    .transform_point3(Vec3::new(local.x, local.y, 0.0)),
                Vec3::Z,
            ),
        };
        // Inverse of generate_ray: x = (1 - 2 ndc.x) tan_half.x.
        let ndc = (Vec2::ONE - plane / self.tan_half) * 0.5;
        let film = ndc / self.inv_size
            - self.film_offset
            - Vec2::new(self.crop_offset[0] as f32, self.crop_offset[1] as f32);
        if !(film.cmpge(Vec2::ZERO).all() && film.cmplt(self.image_size).all()) {
            return None;
        }
        let to = camera_point - p;
        let dist = to.length();
        if !(dist > 0.0) {
            return None;
        }
        let weight = match self.kind {
            Kind::Pinhole | Kind::ThinLens { .. } => {
                let cos = cam_dir.z / cam_dir.length();
                1.0 / (area * cos * cos * cos * dist * dist)
            }
            Kind::Orthographic
            | Kind::Radiancemeter
            | Kind::Irradiancemeter
            | Kind::Distant
            | Kind::Batch => {
                let sx = self.to_world.transform_vector3(Vec3::X).length();
                let sy = self.to_world.transform_vector3(Vec3::Y).length();
                1.0 / (area * sx * sy)
            }
        };
        weight.is_finite().then_some(CameraConnection {
            camera_point,
            dir: to / dist,
            dist,
            film,
            weight,
        })
    }

    /// The solid-angle density of a camera ray's direction `dir` (world, unit) when its film
    /// point is uniform over the whole film: `1 / (A cos^3 theta)`, A the film's area on the
    /// plane z = 1 of camera space and theta the angle to the view axis (for the thin lens,
    /// of the ray from its lens point: the lens point's own density is left out, as in
    /// [`CameraConnection::weight`]). Orthographic cameras have a delta direction: 0. The
    /// bidirectional methods weigh the camera's strategies with it.
    pub fn direction_pdf(&self, dir: Vec3) -> f32 {
        if matches!(
            self.kind,
            Kind::Orthographic
                | Kind::Radiancemeter
                | Kind::Irradiancemeter
                | Kind::Distant
                | Kind::Batch
        ) {
            return 0.0;
        }
        let local = self.to_camera.transform_vector3(dir);
        let cos = local.z / local.length();
        if !(cos > 0.0) {
            return 0.0;
        }
        1.0 / (4.0 * self.tan_half.x * self.tan_half.y * cos * cos * cos)
    }

    /// The camera's centre (the pinhole, the lens's centre, the orthographic film's centre),
    /// world space: where light paths aim at the camera from distant lights.
    pub fn position(&self) -> Vec3 {
        self.origin
    }

    /// The image's size in pixels (a crop window's, or the whole film's).
    pub fn image_size(&self) -> Vec2 {
        self.image_size
    }

    /// Whether the camera sees along one direction only per film point (orthographic): such a
    /// camera cannot see a distant light by a connection from the light.
    pub fn is_orthographic(&self) -> bool {
        self.kind == Kind::Orthographic
    }

    /// Where the scene defines the sensor.
    pub fn loc(&self) -> &pt_scene::SourceLoc {
        &self.loc
    }

    /// Whether the camera is a radiancemeter (one ray), an irradiancemeter, a distant sensor
    /// or a batch: sensors that light paths do not connect to.
    pub fn refuses_light_paths(&self) -> bool {
        matches!(
            self.kind,
            Kind::Radiancemeter | Kind::Irradiancemeter | Kind::Distant | Kind::Batch
        )
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
            principal_point_offset: [0.0; 2],
        };
        let cam = Camera::new(&desc, 200, 100);
        let centre = cam.generate_ray(Vec2::new(100.0, 50.0), Vec2::splat(0.5));
        assert!((centre.dir - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6);
        assert!((centre.tmin - 0.01).abs() < 1e-7);
        // Right edge of the image looks towards world +x at 45 degrees (fov 90 on x).
        let right = cam.generate_ray(Vec2::new(200.0, 50.0), Vec2::splat(0.5));
        assert!(
            (right.dir - Vec3::new(1.0, 0.0, -1.0).normalize()).length() < 1e-6,
            "{:?}",
            right.dir
        );
        // Top edge looks up, with half the tangent (aspect 2:1).
        let top = cam.generate_ray(Vec2::new(100.0, 0.0), Vec2::splat(0.5));
        assert!((top.dir - Vec3::new(0.0, 0.5, -1.0).normalize()).length() < 1e-6);
    }

    fn thin_lens(radius: f32, focus: f32) -> CameraDesc {
        CameraDesc {
            loc: SourceLoc::default(),
            projection: Projection::ThinLens {
                fov_deg: 60.0,
                fov_axis: FovAxis::X,
                aperture_radius: radius,
                focus_distance: focus,
            },
            to_world: lookat(Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.0, 0.5, -1.0), Vec3::Y),
            near_clip: 0.01,
            far_clip: 100.0,
            principal_point_offset: [0.0; 2],
        }
    }

    /// A thin lens of aperture 0 is the pinhole camera, bit for bit, and draws no lens sample.
    #[test]
    fn thin_lens_of_aperture_zero_is_the_pinhole() {
        let mut pinhole = thin_lens(0.0, 3.0);
        let lens = Camera::new(&pinhole, 64, 48);
        let Projection::ThinLens {
            fov_deg, fov_axis, ..
        } = pinhole.projection
        else {
            unreachable!()
        };
        pinhole.projection = Projection::Perspective { fov_deg, fov_axis };
        let pin = Camera::new(&pinhole, 64, 48);
        assert!(!lens.needs_lens_sample());
        for film in [
            Vec2::new(0.3, 0.7),
            Vec2::new(63.9, 47.2),
            Vec2::new(32.0, 24.0),
        ] {
            let (a, b) = (
                lens.generate_ray(film, Vec2::new(0.9, 0.1)),
                pin.generate_ray(film, Vec2::splat(0.5)),
            );
            assert_eq!(
                (a.origin, a.dir, a.tmin, a.tmax),
                (b.origin, b.dir, b.tmin, b.tmax)
            );
        }
    }

    /// The closed forms of the thin lens (Kolb et al. 1995): every ray of a film point, from any
    /// aperture point, crosses the plane of focus (camera z = F) where the pinhole ray does;
    /// on the plane z = D the rays from the aperture's rim lie on a circle of radius
    /// R |1 - D / F| around the pinhole ray's point (the circle of confusion); and the near
    /// clip is the plane z = near.
    #[test]
    fn thin_lens_focuses_and_blurs_by_the_closed_forms() {
        let (r, f) = (0.2, 4.0);
        let desc = thin_lens(r, f);
        let cam = Camera::new(&desc, 64, 48);
        assert!(cam.needs_lens_sample());
        let to_cam = desc.to_world.inverse();
        let at_depth = |ray: &Ray, z: f32| {
            let o = to_cam.transform_point3(ray.origin);
            let d = to_cam.transform_vector3(ray.dir);
            o + d * ((z - o.z) / d.z)
        };
        let film = Vec2::new(20.3, 9.7);
        let pin = Camera::new(&thin_lens(0.0, f), 64, 48).generate_ray(film, Vec2::ZERO);
        for depth in [1.5f32, 4.0, 9.0] {
            let centre = at_depth(&pin, depth);
            for k in 0..16 {
                // Points on the rim of the square map to the rim of the disk.
                let t = k as f32 / 16.0;
                let u = [
                    Vec2::new(t, 0.0),
                    Vec2::new(1.0, t),
                    Vec2::new(1.0 - t, 1.0),
                    Vec2::new(0.0, 1.0 - t),
                ][k % 4];
                let ray = cam.generate_ray(film, u);
                let spread = (at_depth(&ray, depth) - centre).truncate().length();
                let expect = r * (1.0 - depth / f).abs();
                assert!(
                    (spread - expect).abs() < 1e-4,
                    "depth {depth}: {spread} vs {expect}"
                );
                let near = to_cam.transform_point3(ray.origin + ray.dir * ray.tmin);
                assert!((near.z - 0.01).abs() < 1e-6, "{near}");
            }
        }
    }

    /// The orthographic camera: parallel rays along the view axis from the rectangle
    /// [-1, 1] x [-1/aspect, 1/aspect] of camera space, +x to the image's left, scaled by
    /// `to_world`; film corners map to its corners exactly.
    #[test]
    fn orthographic_rays_start_on_the_film_rectangle() {
        let to_world = Mat4::from_translation(Vec3::new(0.0, 0.0, -2.0))
            * Mat4::from_scale(Vec3::new(3.0, 3.0, 1.0));
        let desc = CameraDesc {
            loc: SourceLoc::default(),
            projection: Projection::Orthographic,
            to_world,
            near_clip: 0.5,
            far_clip: 10.0,
            principal_point_offset: [0.0; 2],
        };
        let cam = Camera::new(&desc, 40, 20);
        assert!(!cam.needs_lens_sample());
        let top_left = cam.generate_ray(Vec2::ZERO, Vec2::ZERO);
        assert_eq!(top_left.origin, Vec3::new(3.0, 1.5, -2.0));
        assert_eq!(top_left.dir, Vec3::Z);
        assert_eq!((top_left.tmin, top_left.tmax), (0.5, 10.0));
        let bottom_right = cam.generate_ray(Vec2::new(40.0, 20.0), Vec2::ZERO);
        assert_eq!(bottom_right.origin, Vec3::new(-3.0, -1.5, -2.0));
        // One pixel is 2 / 40 of the unscaled width: 0.15 in the world.
        let next = cam.generate_ray(Vec2::new(1.0, 0.0), Vec2::ZERO);
        assert!((top_left.origin.x - next.origin.x - 0.15).abs() < 1e-6);
    }

    /// `connect` inverts `generate_ray` for every camera, with a crop window and a principal
    /// point offset: a point on the ray through a film position (with the same lens point)
    /// lands at that film position, seen along the reversed ray.
    #[test]
    fn connect_inverts_generate_ray() {
        let to_world = lookat(Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.0, 0.5, -1.0), Vec3::Y);
        let film = pt_scene::FilmDesc {
            width: 40,
            height: 30,
            crop: Some(pt_scene::CropWindow {
                offset: [7, 5],
                film_size: [64, 48],
            }),
            filter: pt_scene::FilterDesc::Box { radius: 0.5 },
            sample_border: false,
            reconstruction: pt_scene::Reconstruction::Splat,
            pixel_format: pt_scene::PixelFormat::Rgb,
        };
        for projection in [
            Projection::Perspective {
                fov_deg: 50.0,
                fov_axis: FovAxis::X,
            },
            Projection::ThinLens {
                fov_deg: 50.0,
                fov_axis: FovAxis::Y,
                aperture_radius: 0.2,
                focus_distance: 3.0,
            },
            Projection::Orthographic,
        ] {
            let desc = CameraDesc {
                loc: SourceLoc::default(),
                projection,
                to_world,
                near_clip: 0.01,
                far_clip: 100.0,
                principal_point_offset: [0.1, -0.05],
            };
            let cam = Camera::for_film(&desc, &film);
            for (x, y, off, lens, t) in [
                (3, 4, Vec2::new(0.2, -0.3), Vec2::new(0.3, 0.8), 2.0),
                (39, 0, Vec2::new(0.49, -0.49), Vec2::new(0.9, 0.1), 5.0),
                (20, 29, Vec2::new(-0.1, 0.4), Vec2::new(0.5, 0.5), 0.7),
            ] {
                let ray = cam.pixel_ray(x, y, off, lens);
                let p = ray.origin + ray.dir * t;
                let c = cam.connect(p, lens).expect("the point is in view");
                let want = Vec2::new(x as f32 + 0.5, y as f32 + 0.5) + off;
                assert!(
                    (c.film - want).length() < 2e-3,
                    "{projection:?}: {} vs {want}",
                    c.film
                );
                assert!((c.dir + ray.dir).length() < 1e-4, "{projection:?}");
                assert!(
                    (c.camera_point - ray.origin).length() < 1e-4,
                    "{projection:?}"
                );
                // The ray's direction density is the connection's weight without the
                // distance falloff (both 1 / (A cos^3)).
                if projection != Projection::Orthographic {
                    let pdf = cam.direction_pdf(ray.dir);
                    assert!(
                        (pdf / (c.weight * c.dist * c.dist) - 1.0).abs() < 1e-3,
                        "{projection:?}"
                    );
                }
            }
            // Behind the camera: nothing.
            let behind = to_world.transform_point3(Vec3::new(0.0, 0.0, -1.0));
            assert!(cam.connect(behind, Vec2::splat(0.5)).is_none());
        }
    }

    /// The importance integrates to 1 over the film (the normalisation the light tracer's
    /// pixels rely on): for the perspective cameras, the mean of `weight d^2 / p(w)` over
    /// directions uniform on the sphere (p = 1 / 4 pi), points at distance d = 2, equals 1; for
    /// the thin lens also averaged over lens points. 2^18 samples: the estimate's relative
    /// standard error is sqrt(4 pi / (film solid angle) - 1) / 512, about 1% for this 60
    /// degree film; 4% is four of them. A factor such as cos^3 for cos^4 moves it by more.
    #[test]
    fn importance_integrates_to_one() {
        for projection in [
            Projection::Perspective {
                fov_deg: 60.0,
                fov_axis: FovAxis::X,
            },
            Projection::ThinLens {
                fov_deg: 60.0,
                fov_axis: FovAxis::X,
                aperture_radius: 0.05,
                focus_distance: 1.5,
            },
        ] {
            let desc = CameraDesc {
                loc: SourceLoc::default(),
                projection,
                to_world: lookat(Vec3::ZERO, Vec3::new(0.3, -0.2, -1.0), Vec3::Y),
                near_clip: 0.01,
                far_clip: 100.0,
                principal_point_offset: [0.0; 2],
            };
            let cam = Camera::new(&desc, 48, 32);
            let mut rng = crate::sampler::Sampler::new(7, 0, 0);
            let n = 1 << 18;
            let mut sum = 0.0f64;
            for _ in 0..n {
                let d = pt_math::warp::square_to_uniform_sphere(rng.next_2d());
                if let Some(c) = cam.connect(d * 2.0, rng.next_2d()) {
                    sum += f64::from(c.weight * c.dist * c.dist) * 4.0 * std::f64::consts::PI;
                }
            }
            let mean = sum / n as f64;
            assert!((mean - 1.0).abs() < 0.04, "{projection:?}: {mean}");
        }
    }
}
