//! Lights that are not attached to a shape, from their descriptions.

use super::{EnvMap, Light, SpotCone};
use crate::scene::BuildError;
use crate::texture::{constant_spectrum, Role};
use pt_math::{Frame, Mat3, Vec3};
use pt_scene::{LightDesc, LightKind};
use pt_spectrum::ColorMode;

/// A light that is not attached to a shape, in the scene's colour mode (spectral mode: RGB
/// emission upsampled and multiplied by D65; environment maps upsampled per texel).
pub fn build_light(l: &LightDesc, mode: ColorMode) -> Result<Light, BuildError> {
    let err = |m: String| BuildError {
        loc: l.loc.clone(),
        message: m,
    };
    let emission = |s| constant_spectrum(s, Role::Emission, mode);
    Ok(match &l.kind {
        LightKind::Point {
            position,
            intensity,
        } => Light::Point {
            position: *position,
            intensity: emission(intensity),
        },
        LightKind::Spot {
            to_world,
            intensity,
            cutoff_deg,
            beam_width_deg,
        } => {
            let axis = to_world
                .transform_vector3(Vec3::Z)
                .try_normalize()
                .ok_or_else(|| err("spot to_world has no direction".into()))?;
            let cutoff = cutoff_deg.to_radians();
            Light::Spot {
                position: to_world.transform_point3(Vec3::ZERO),
                frame: Frame::from_normal(axis),
                intensity: emission(intensity),
                cone: SpotCone {
                    cos_cutoff: cutoff.cos(),
                    cutoff,
                    beam_width: beam_width_deg.to_radians(),
                },
            }
        }
        LightKind::Directional {
            direction,
            irradiance,
        } => Light::Directional {
            to_light: -*direction,
            irradiance: emission(irradiance),
        },
        LightKind::Sun {
            direction,
            irradiance,
            angular_diameter_deg,
        } => {
            let alpha = 0.5 * angular_diameter_deg.to_radians();
            let half = (0.5 * alpha).sin();
            let one_minus_cos = 2.0 * half * half; // 1 - cos(alpha) without cancellation
            let sin2 = one_minus_cos * (2.0 - one_minus_cos);
            Light::Sun {
                frame: Frame::from_normal(-*direction),
                irradiance: emission(irradiance),
                to_radiance: 1.0 / (std::f32::consts::PI * sin2),
                one_minus_cos,
            }
        }
        LightKind::Constant { radiance } => Light::Constant {
            radiance: emission(radiance),
        },
        LightKind::EnvMap {
            filename,
            to_world,
            scale,
        } => {
            let (img, _) =
                pt_image::read_exr(filename).map_err(|e| err(format!("environment map: {e}")))?;
            if img
                .data
                .iter()
                .any(|p| p.iter().any(|c| !c.is_finite() || *c < 0.0))
            {
                return Err(err(format!(
                    "environment map '{}' has negative or non-finite pixels",
                    filename.display()
                )));
            }
            let texels = img.data.iter().map(|p| p.map(|c| c * scale)).collect();
            let rot = Mat3::from_mat4(*to_world);
            let mut e = EnvMap::new(img.width as usize, img.height as usize, texels, rot)
                .ok_or_else(|| err("empty environment map".into()))?;
            // Spectral mode: the upsampled texels times D65 of luminance 1 (Mitsuba 3's envmap).
            if mode == ColorMode::Spectral {
                e.upsample();
            }
            Light::EnvMap(e)
        }
    })
}
