//! Lights and cameras: KHR_lights_punctual, the camera in use (a node's or the default one
//! framing the scene), and the default environment when nothing emits.

use super::{Ctx, GltfError, DEFAULT_FOV_Y_DEG, DEFAULT_WIDTH};
use crate::ir::{
    CameraDesc, FovAxis, Geometry, LightDesc, LightKind, Projection, SceneDesc, ShapeDesc,
    SpectrumDesc,
};
use glam::{Mat4, Vec3};

/// A node with a camera, and its world transform.
pub(super) struct CameraNode<'d> {
    pub camera: gltf::Camera<'d>,
    pub world: Mat4,
    pub node: usize,
}

/// glTF's camera space (looking down -z, +x right) to the renderer's (down +z, +x left).
const GLTF_TO_CAMERA: Vec3 = Vec3::new(-1.0, 1.0, -1.0);

/// Whether `x` is finite and >= 0.
fn non_negative(x: f32) -> bool {
    x.is_finite() && x >= 0.0
}

/// A KHR_lights_punctual light at a node (photometric values used 1:1: see the module doc).
pub(super) fn map_light(
    cx: &mut Ctx,
    light: &gltf::khr_lights_punctual::Light,
    world: Mat4,
    node: usize,
) -> Result<LightDesc, GltfError> {
    use gltf::khr_lights_punctual::Kind;
    let elem = format!(
        "KHR_lights_punctual.lights[{}] (node {node})",
        light.index()
    );
    let (c, i) = (light.color(), light.intensity());
    if !non_negative(i) || !c.iter().all(|x| non_negative(*x)) {
        return Err(cx.err(format!(
            "{elem}: intensity and colour must be finite and >= 0"
        )));
    }
    if light.range().is_some() {
        cx.warnings.push(format!(
            "{elem}: range ignored (physical inverse-square falloff)"
        ));
    }
    // cd -> intensity per sr, lx -> irradiance per m^2.
    let value = SpectrumDesc::Rgb(c.map(|x| x * i));
    let position = world.transform_point3(Vec3::ZERO);
    let dir = world
        .transform_vector3(-Vec3::Z)
        .try_normalize()
        .ok_or_else(|| cx.err(format!("{elem}: the node's transform has no direction")))?;
    let kind = match light.kind() {
        Kind::Point => LightKind::Point {
            position,
            intensity: value,
            profile: None,
        },
        Kind::Directional => LightKind::Directional {
            direction: dir,
            irradiance: value,
        },
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => spot(
            cx,
            &elem,
            position,
            dir,
            value,
            inner_cone_angle,
            outer_cone_angle,
        )?,
    };
    Ok(LightDesc {
        loc: cx.loc(elem),
        kind,
    })
}

/// A spot light at `position` pointing along `dir`, full within `inner` and off beyond
/// `outer` (radians).
fn spot(
    cx: &Ctx,
    elem: &str,
    position: Vec3,
    dir: Vec3,
    intensity: SpectrumDesc,
    inner: f32,
    outer: f32,
) -> Result<LightKind, GltfError> {
    let valid =
        outer > 0.0 && outer <= std::f32::consts::FRAC_PI_2 && inner >= 0.0 && inner < outer;
    if !valid {
        return Err(cx.err(format!(
            "{elem}: need 0 <= innerConeAngle < outerConeAngle <= pi/2, got {inner}, {outer}"
        )));
    }
    // The renderer's spot points along its +z: a rotation taking +z to the glTF axis.
    let rot = glam::Quat::from_rotation_arc(Vec3::Z, dir);
    Ok(LightKind::Spot {
        to_world: Mat4::from_rotation_translation(rot, position),
        intensity,
        cutoff_deg: outer.to_degrees(),
        beam_width_deg: inner.to_degrees(),
        texture: None,
        profile: None,
    })
}

/// A light for `pt info`.
fn describe_light(k: &LightKind) -> String {
    match k {
        LightKind::Point {
            position,
            intensity,
            ..
        } => format!("point at {position:.3}, intensity {intensity:?} (cd -> per sr, 1:1)"),
        LightKind::Spot {
            intensity,
            cutoff_deg,
            beam_width_deg,
            to_world,
            ..
        } => {
            format!("spot at {:.3}, intensity {intensity:?} (cd, 1:1), full to {beam_width_deg:.2} deg, off beyond {cutoff_deg:.2} deg", to_world.transform_point3(Vec3::ZERO))
        }
        LightKind::Directional {
            direction,
            irradiance,
        } => format!(
            "directional towards {direction:.3}, irradiance {irradiance:?} (lux -> per m^2, 1:1)"
        ),
        other => format!("{other:?}"),
    }
}

/// Lists the lights for `pt info` and adds the default environment when nothing emits.
pub(super) fn finish_lights(cx: &mut Ctx, desc: &mut SceneDesc) {
    let emissive = desc.shapes.iter().filter(|s| s.emitter.is_some()).count();
    cx.summary.push(format!(
        "lights      {} punctual, {emissive} emissive primitive(s)",
        desc.lights.len()
    ));
    for l in &desc.lights {
        cx.summary
            .push(format!("  {}: {}", l.loc.element, describe_light(&l.kind)));
    }
    if desc.lights.is_empty() && emissive == 0 {
        desc.lights.push(LightDesc {
            loc: cx.loc("default environment".into()),
            kind: LightKind::Constant {
                radiance: SpectrumDesc::Constant(1.0),
            },
        });
        cx.warnings.push("no light and no emissive material: using the default environment (constant radiance 1, white)".into());
    }
}

/// Lists the cameras for `pt info` and sets the scene's camera: the chosen one (`choice`, or
/// the first perspective camera), else the default camera framing the scene's bounds.
pub(super) fn set_camera(
    cx: &mut Ctx,
    cameras: &[CameraNode],
    choice: Option<usize>,
    desc: &mut SceneDesc,
) -> Result<(), GltfError> {
    cx.summary.push(format!(
        "cameras     {} (in node order; choose with --camera N)",
        cameras.len()
    ));
    for (i, c) in cameras.iter().enumerate() {
        let kind = match c.camera.projection() {
            gltf::camera::Projection::Perspective(p) => format!(
                "perspective, yfov {:.2} deg, aspect {:?}",
                p.yfov().to_degrees(),
                p.aspect_ratio()
            ),
            gltf::camera::Projection::Orthographic(_) => "orthographic (not supported)".into(),
        };
        cx.summary
            .push(format!("  camera {i}: node {}, {kind}", c.node));
    }
    match choose_camera(cx, cameras, choice)? {
        Some(i) => {
            node_camera(cx, &cameras[i], desc)?;
            if cameras.len() > 1 {
                cx.warnings.push(format!(
                    "using camera {i} of {} (choose another with --camera N)",
                    cameras.len()
                ));
            }
        }
        None => default_camera(cx, desc),
    }
    Ok(())
}

/// The camera to use: `choice` (which must exist and be perspective), or the first
/// perspective camera; `None` when there is none.
fn choose_camera(
    cx: &Ctx,
    cameras: &[CameraNode],
    choice: Option<usize>,
) -> Result<Option<usize>, GltfError> {
    let is_perspective = |c: &CameraNode| {
        matches!(
            c.camera.projection(),
            gltf::camera::Projection::Perspective(_)
        )
    };
    match choice {
        Some(n) if n < cameras.len() => {
            if !is_perspective(&cameras[n]) {
                return Err(cx.err(format!(
                    "camera {n} is orthographic: only perspective cameras are supported"
                )));
            }
            Ok(Some(n))
        }
        Some(n) => Err(cx.err(format!(
            "--camera {n}: the file has {} camera(s) (0-based)",
            cameras.len()
        ))),
        None => Ok(cameras.iter().position(is_perspective)),
    }
}

/// A node's perspective camera: `yfov` vertical, clip planes, and the image height from
/// `aspectRatio`.
fn node_camera(cx: &Ctx, c: &CameraNode, desc: &mut SceneDesc) -> Result<(), GltfError> {
    let gltf::camera::Projection::Perspective(p) = c.camera.projection() else {
        return Ok(()); // `choose_camera` only picks perspective cameras
    };
    let yfov = p.yfov().to_degrees();
    if !(yfov > 0.0 && yfov < 180.0) {
        return Err(cx.err(format!(
            "cameras[{}]: yfov {} rad is not in (0, pi)",
            c.camera.index(),
            p.yfov()
        )));
    }
    desc.camera = CameraDesc {
        loc: cx.loc(format!("cameras[{}] (node {})", c.camera.index(), c.node)),
        projection: Projection::Perspective {
            fov_deg: yfov,
            fov_axis: FovAxis::Y,
        },
        to_world: c.world * Mat4::from_scale(GLTF_TO_CAMERA),
        near_clip: p.znear().max(1e-6),
        far_clip: p.zfar().unwrap_or(1e6),
        principal_point_offset: [0.0; 2],
    };
    if let Some(a) = p.aspect_ratio().filter(|a| *a > 0.0 && a.is_finite()) {
        desc.film.height = ((DEFAULT_WIDTH as f32 / a).round() as u32).max(1);
    }
    Ok(())
}

/// The default camera: on the +z side of the bounds' centre, looking down -z, at the distance
/// where the bounding sphere fits the vertical fov (x 1.1).
fn default_camera(cx: &mut Ctx, desc: &mut SceneDesc) {
    let (c, r) = scene_bounds(&desc.shapes);
    let dist = 1.1 * r / (0.5 * DEFAULT_FOV_Y_DEG.to_radians()).sin();
    let eye = c + Vec3::Z * dist;
    // A glTF camera at `eye` with no rotation looks down -z with +y up.
    desc.camera.to_world = Mat4::from_translation(eye) * Mat4::from_scale(GLTF_TO_CAMERA);
    desc.camera.near_clip = (dist - r).max(dist * 1e-3) * 0.5;
    desc.camera.far_clip = (dist + r) * 2.0;
    cx.warnings.push(format!(
        "no perspective camera: using the default camera (vertical fov {DEFAULT_FOV_Y_DEG} deg at ({:.3}, {:.3}, {:.3}) looking down -z at the bounds' centre ({:.3}, {:.3}, {:.3}), radius {:.3})",
        eye.x, eye.y, eye.z, c.x, c.y, c.z, r
    ));
}

/// Centre and radius of the bounding sphere of the boxes of all meshes (a unit sphere at the
/// origin when empty).
fn scene_bounds(shapes: &[ShapeDesc]) -> (Vec3, f32) {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for s in shapes {
        if let Geometry::Mesh(m) = &s.geometry {
            for p in &m.positions {
                lo = lo.min(*p);
                hi = hi.max(*p);
            }
        }
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return (Vec3::ZERO, 1.0);
    }
    (0.5 * (lo + hi), (0.5 * (hi - lo).length()).max(1e-3))
}
