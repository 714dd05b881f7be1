//! Lights that are not attached to a shape, from their descriptions.

use super::{envmap_table, EnvMap, IntensityProfile, Light, Projector, SpotCone, SpotTexture};
use crate::camera::tan_half_x;
use crate::scene::BuildError;
use crate::texture::{constant_spectrum, Role, TextureBuilder};
use pt_math::{Frame, Mat3, Mat4, Vec3};
use pt_scene::{LightDesc, LightKind, ProfileSource};
use pt_spectrum::ColorMode;

/// A light that is not attached to a shape, in the scene's colour mode (spectral mode: RGB
/// emission upsampled and multiplied by D65; environment maps upsampled per texel). Textures
/// (a spot's image, a projector's) are built by `textures`.
pub fn build_light(
    l: &LightDesc,
    mode: ColorMode,
    textures: &mut TextureBuilder,
) -> Result<Light, BuildError> {
    let err = |m: String| BuildError {
        loc: l.loc.clone(),
        message: m,
    };
    let emission = |s| constant_spectrum(s, Role::Emission, mode);
    Ok(match &l.kind {
        LightKind::Point {
            position,
            intensity,
            profile,
        } => {
            let intensity = emission(intensity);
            let profile = match profile {
                Some(p) => Some(Box::new(build_profile(p, &intensity, None).map_err(err)?)),
                None => None,
            };
            Light::Point {
                position: *position,
                intensity,
                profile,
            }
        }
        LightKind::Spot { .. } => build_spot(&l.kind, mode, textures).map_err(err)?,
        LightKind::Projector { .. } => build_projector(&l.kind, textures).map_err(err)?,
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
        LightKind::SunSky(s) => build_sunsky(s, mode).map_err(err)?,
        LightKind::Constant { radiance } => Light::Constant {
            radiance: emission(radiance),
        },
        LightKind::EnvMap { .. } => build_envmap(&l.kind, mode).map_err(err)?,
    })
}

/// World-to-light linear map of a light's `to_world` (for texture lookups).
fn world_to_local(m: &Mat4) -> Result<Mat3, String> {
    let inv = Mat3::from_mat4(*m).inverse();
    if inv.is_finite() {
        Ok(inv)
    } else {
        Err("to_world cannot be inverted (a zero scale?)".into())
    }
}

/// A `spot` light: its cone, optional IES profile and optional texture (built by `textures`).
fn build_spot(
    kind: &LightKind,
    mode: ColorMode,
    textures: &mut TextureBuilder,
) -> Result<Light, String> {
    let LightKind::Spot {
        to_world,
        intensity,
        cutoff_deg,
        beam_width_deg,
        texture,
        profile,
    } = kind
    else {
        return Err("internal: not a spot light".into());
    };
    let axis = to_world
        .transform_vector3(Vec3::Z)
        .try_normalize()
        .ok_or_else(|| "spot to_world has no direction".to_string())?;
    let cutoff = cutoff_deg.to_radians();
    let cone = SpotCone {
        cos_cutoff: cutoff.cos(),
        cutoff,
        beam_width: beam_width_deg.to_radians(),
    };
    let intensity = constant_spectrum(intensity, Role::Emission, mode);
    let profile = match profile {
        Some(p) => Some(Box::new(build_profile(p, &intensity, Some(&cone))?)),
        None => None,
    };
    Ok(Light::Spot {
        position: to_world.transform_point3(Vec3::ZERO),
        frame: Frame::from_normal(axis),
        intensity,
        cone,
        profile,
        texture: match texture {
            Some(t) => Some(Box::new(SpotTexture {
                texture: textures.build(t, Role::Albedo)?,
                to_local: world_to_local(to_world)?,
                inv_tan_cutoff: 1.0 / cutoff.tan(),
            })),
            None => None,
        },
    })
}

/// A `projector`: its irradiance texture (built by `textures`) through a perspective
/// projection.
fn build_projector(kind: &LightKind, textures: &mut TextureBuilder) -> Result<Light, String> {
    let LightKind::Projector {
        to_world,
        irradiance,
        scale,
        projection,
    } = kind
    else {
        return Err("internal: not a projector".into());
    };
    // Mitsuba 3.9.1 reads the projector's image (and a spot's) as a plain texture: in
    // spectral mode texels are upsampled as reflectances, without D65 (the spot's
    // intensity carries D65).
    let irradiance = textures.build(irradiance, Role::Albedo)?;
    let (w, h) = irradiance.resolution();
    let pt_scene::Projection::Perspective { fov_deg, fov_axis } = *projection else {
        return Err("a projector's projection must be perspective".into());
    };
    let tan_half = tan_half_x(fov_deg, fov_axis, w as f32, h as f32);
    Ok(Light::Projector(Box::new(Projector {
        position: to_world.transform_point3(Vec3::ZERO),
        to_local: world_to_local(to_world)?,
        axis: to_world.transform_vector3(Vec3::Z),
        irradiance,
        pi_scale: std::f32::consts::PI * scale,
        cot_half_x: 1.0 / tan_half,
        aspect: w as f32 / h as f32,
    })))
}

/// An `envmap`: the EXR's texels times `scale` (non-negative and finite), upsampled in
/// spectral mode.
fn build_envmap(kind: &LightKind, mode: ColorMode) -> Result<Light, String> {
    let LightKind::EnvMap {
        filename,
        to_world,
        scale,
    } = kind
    else {
        return Err("internal: not an environment map".into());
    };
    let (img, _) = pt_image::read_exr(filename).map_err(|e| format!("environment map: {e}"))?;
    if img
        .data
        .iter()
        .any(|p| p.iter().any(|c| !c.is_finite() || *c < 0.0))
    {
        return Err(format!(
            "environment map '{}' has negative or non-finite pixels",
            filename.display()
        ));
    }
    let texels = img.data.iter().map(|p| p.map(|c| c * scale)).collect();
    let rot = Mat3::from_mat4(*to_world);
    let mut e = EnvMap::new(img.width as usize, img.height as usize, texels, rot)
        .ok_or_else(|| "empty environment map".to_string())?;
    // Spectral mode: the upsampled texels times D65 of luminance 1 (Mitsuba 3's envmap).
    if mode == ColorMode::Spectral {
        e.upsample();
    }
    Ok(Light::EnvMap(e))
}

/// A light's intensity profile: an IES table (its values per unit luminance of the light's
/// colour, so the colour's luminance is divided out) or an equirectangular EXR whose pixels'
/// luminance multiplies the intensity; `cone` is a spot's falloff.
fn build_profile(
    p: &pt_scene::IntensityProfile,
    intensity: &crate::texture::ConstantSpectrum,
    cone: Option<&SpotCone>,
) -> Result<IntensityProfile, String> {
    let (table, scale) = match &p.source {
        ProfileSource::Ies(table) => {
            let lum = intensity.luminance();
            if !(lum > 0.0) {
                return Err("the intensity of a light with an IES profile sets its colour, which must not be black".into());
            }
            (std::borrow::Cow::Borrowed(table), p.scale / lum)
        }
        ProfileSource::Image(path) => {
            let (img, _) =
                pt_image::read_exr(path).map_err(|e| format!("goniometric image: {e}"))?;
            if img.height < 2 {
                return Err(format!(
                    "goniometric image '{}' needs at least two rows (its poles)",
                    path.display()
                ));
            }
            let values: Vec<f32> = img
                .data
                .iter()
                .map(|px| crate::texture::luminance(*px))
                .collect();
            if values.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
                return Err(format!(
                    "goniometric image '{}' has negative or non-finite pixels",
                    path.display()
                ));
            }
            let table = envmap_table(img.width as usize, img.height as usize, values);
            (std::borrow::Cow::Owned(table), p.scale)
        }
    };
    IntensityProfile::new(&table, scale, p.to_world, cone).map_err(|e| e.to_string())
}

/// The sun and sky: the model in the scene's colour mode (spectral mode: the albedo at the
/// model's 11 wavelengths; RGB mode: its RGB reflectance), an RGB model for the sampling
/// densities, and a black light when the sun is below the horizon (the model is 0 there, as
/// Mitsuba's, which warns).
fn build_sunsky(s: &pt_scene::SunSkyDesc, mode: ColorMode) -> Result<Light, String> {
    use crate::texture::{rgb_of, spectrum_for_role};
    let params = pt_sky::SkyParams {
        turbidity: s.turbidity,
        sun_dir: s.sun_local,
        sun_half_aperture: (0.5 * s.sun_aperture_deg).to_radians(),
        complex_sun: s.complex_sun,
        sun_scale: s.sun_scale,
        sky_scale: s.sky_scale,
    };
    let albedo_rgb = rgb_of(&s.albedo, Role::Albedo);
    let rgb = pt_sky::SkyModel::rgb(&params, albedo_rgb);
    let model = match mode {
        ColorMode::Rgb => rgb.clone(),
        ColorMode::Spectral => {
            let spectrum = spectrum_for_role(&s.albedo, Role::Albedo);
            let albedo = std::array::from_fn(|c| {
                spectrum.eval(
                    pt_sky::tables::WAVELENGTH_MIN + pt_sky::tables::WAVELENGTH_STEP * c as f32,
                )
            });
            pt_sky::SkyModel::spectral(&params, albedo)
        }
    };
    Ok(match super::SunSky::new(model, &rgb, s.to_world) {
        Some(light) => Light::SunSky(Box::new(light)),
        None => Light::Constant {
            radiance: crate::texture::ConstantSpectrum::Rgb(pt_spectrum::SampledSpectrum::ZERO),
        },
    })
}
