//! [`Integrator::from_desc`]: a method and its settings read once from the scene's
//! `<integrator>` with the command line's [`Overrides`] applied. An override that does not
//! apply to the chosen method is an error, checked here so that no method ignores a setting
//! silently.

use crate::{direct, photonmap, sppm, vcm};
use crate::{Integrator, IntegratorError, Overrides, PathSettings, PathTracer, Strategy};
use pt_radiosity::RadiosityParams;
use pt_scene::{IntegratorDesc, IntegratorKind, RadiosityOptions};

/// The error of a setting that is out of range or does not apply.
fn bad<T>(m: String) -> Result<T, IntegratorError> {
    Err(IntegratorError::Settings(m))
}

impl Integrator {
    /// The method the scene's `<integrator>` asks for (or `o.kind`), with its settings read
    /// from the description once and the command line's overrides applied. An override that
    /// does not apply to the method is an error.
    pub fn from_desc(d: &IntegratorDesc, o: &Overrides) -> Result<Integrator, IntegratorError> {
        check_ranges(o)?;
        // Naming the scene's own method keeps the scene's parameters for it.
        let kind = match o.kind {
            Some(k) if std::mem::discriminant(&k) != std::mem::discriminant(&d.kind) => k,
            _ => d.kind,
        };
        let radiosity_options = o.radiosity != RadiosityOptions::default();
        if kind != IntegratorKind::Radiosity && radiosity_options {
            return bad("radiosity options apply to --integrator radiosity only".into());
        }
        // The scene's settings for the method chosen (which may not be the scene's).
        let scene_settings = PathSettings::from_desc(&IntegratorDesc { kind, ..d.clone() });
        let path = |max_depth: i32| PathTracer {
            settings: PathSettings {
                max_depth: o.max_depth.unwrap_or(max_depth),
                strategy: o.strategy.unwrap_or(scene_settings.strategy),
                ..scene_settings
            },
            clamp: o.clamp,
        };
        if let Some(time) = o.afterglow {
            return afterglow(kind, time, path(d.max_depth));
        }
        Ok(match kind {
            // A radiosity scene rendered by the path tracer keeps its max_depth.
            IntegratorKind::Path | IntegratorKind::VolPath => Integrator::Path(path(d.max_depth)),
            IntegratorKind::Direct {
                emitter_samples,
                bsdf_samples,
            } => direct_illumination(emitter_samples, bsdf_samples, o, path(2))?,
            IntegratorKind::PTracer { samples_per_pass } => {
                refuse_path_tracer_options(o, "ptracer")?;
                Integrator::PTracer {
                    settings: path(d.max_depth).settings,
                    samples_per_pass,
                }
            }
            IntegratorKind::Sppm {
                photons_per_iteration,
                initial_radius,
                alpha,
            } => {
                refuse_path_tracer_options(o, "sppm")?;
                Integrator::Sppm {
                    settings: path(d.max_depth).settings,
                    sppm: sppm::SppmSettings {
                        photons: photons_per_iteration.map(u64::from),
                        initial_radius,
                        alpha,
                    },
                }
            }
            IntegratorKind::PhotonMapper {
                global_photons,
                caustic_photons,
                lookup_size,
                lookup_radius,
                final_gather,
            } => {
                refuse_path_tracer_options(o, "photonmapper")?;
                Integrator::PhotonMapper {
                    settings: path(d.max_depth).settings,
                    photons: photonmap::PhotonMapSettings {
                        global_photons: u64::from(global_photons),
                        caustic_photons: u64::from(caustic_photons),
                        lookup: lookup_size as usize,
                        max_radius: lookup_radius,
                        final_gather,
                    },
                }
            }
            IntegratorKind::Bdpt | IntegratorKind::Vcm { .. } => {
                bidirectional(kind, o, path(d.max_depth).settings)?
            }
            IntegratorKind::Depth => {
                if o.max_depth.is_some() || o.strategy.is_some() || o.clamp.is_some() {
                    return bad(
                        "--max-depth, --strategy and --clamp apply to the path tracers, not to depth"
                            .into(),
                    );
                }
                Integrator::Depth
            }
            IntegratorKind::Radiosity => {
                if o.max_depth.is_some() || o.clamp.is_some() || o.strategy.is_some() {
                    return bad("--max-depth, --clamp and --strategy apply to the path tracer, not to radiosity".into());
                }
                Integrator::Radiosity(radiosity_params(&d.radiosity, &o.radiosity))
            }
        })
    }
}

/// Refuses a `--max-depth` or `--clamp` out of range, whatever the method.
fn check_ranges(o: &Overrides) -> Result<(), IntegratorError> {
    if let Some(depth) = o.max_depth {
        if depth < -1 {
            return bad(format!(
                "--max-depth must be -1 (unlimited) or >= 0, got {depth}"
            ));
        }
    }
    if let Some(c) = o.clamp {
        if !(c > 0.0 && c.is_finite()) {
            return bad(format!(
                "--clamp must be a positive finite radiance, got {c}"
            ));
        }
    }
    Ok(())
}

/// The afterglow `time` seconds after the lights went out, rendered by the path tracer `path`;
/// refused for the methods that are not path tracers.
fn afterglow(
    kind: IntegratorKind,
    time: f32,
    path: PathTracer,
) -> Result<Integrator, IntegratorError> {
    if !kind.is_camera_path_tracer() {
        return bad("--time (afterglow) is rendered by the path tracer".into());
    }
    if !(time >= 0.0 && time.is_finite()) {
        return bad(format!(
            "--time must be a non-negative number of seconds, got {time}"
        ));
    }
    Ok(Integrator::Afterglow { time, path })
}

/// Mitsuba's `direct` with the scene's numbers of light and BSDF samples, which `--strategy`
/// narrows to one strategy (or both) at the larger count; `path` is the path tracer of depth 2.
fn direct_illumination(
    emitter_samples: u32,
    bsdf_samples: u32,
    o: &Overrides,
    mut path: PathTracer,
) -> Result<Integrator, IntegratorError> {
    if o.max_depth.is_some() {
        return bad(
            "--max-depth applies to path and volpath; direct shades the first hit only".into(),
        );
    }
    // --strategy keeps one strategy with the larger count, or both.
    let most = emitter_samples.max(bsdf_samples);
    let counts = match o.strategy {
        None => (emitter_samples, bsdf_samples),
        Some(Strategy::Mis) => (most, most),
        Some(Strategy::Light) => (most, 0),
        Some(Strategy::Bsdf) => (0, most),
    };
    path.settings.direct = Some(direct::ShadingSamples {
        emitter: counts.0,
        bsdf: counts.1,
    });
    Ok(Integrator::Direct(path))
}

/// Refuses `--clamp` and `--strategy`, which only the path tracer has, for the method `name`
/// that traces light paths.
fn refuse_path_tracer_options(o: &Overrides, name: &str) -> Result<(), IntegratorError> {
    if o.clamp.is_some() || o.strategy.is_some() {
        return bad(format!(
            "--clamp and --strategy apply to the path tracer, not to {name}"
        ));
    }
    Ok(())
}

/// Bidirectional path tracing (`kind` is `Bdpt`) or vertex connection and merging with the
/// scene's radius schedule.
fn bidirectional(
    kind: IntegratorKind,
    o: &Overrides,
    settings: PathSettings,
) -> Result<Integrator, IntegratorError> {
    let params = match kind {
        IntegratorKind::Vcm {
            initial_radius,
            alpha,
        } => vcm::VcmSettings {
            initial_radius,
            alpha,
            ..vcm::VcmSettings::vcm()
        },
        _ => vcm::VcmSettings::bdpt(),
    };
    refuse_path_tracer_options(o, params.name())?;
    Ok(Integrator::Vcm {
        settings,
        vcm: params,
    })
}

/// The radiosity parameters: the scene's options, each overridden by the command line's.
fn radiosity_params(scene: &RadiosityOptions, cli: &RadiosityOptions) -> RadiosityParams {
    let d = RadiosityParams::default();
    RadiosityParams {
        patch_size: cli.patch_size.or(scene.patch_size).or(d.patch_size),
        rays_per_patch: cli
            .rays_per_patch
            .or(scene.rays_per_patch)
            .unwrap_or(d.rays_per_patch),
        tolerance: cli.tolerance.or(scene.tolerance).unwrap_or(d.tolerance),
        max_iterations: cli
            .max_iterations
            .or(scene.max_iterations)
            .unwrap_or(d.max_iterations),
        solver: cli.solver.or(scene.solver).unwrap_or(d.solver),
        display: cli.display.or(scene.display).unwrap_or(d.display),
        reciprocity: cli
            .reciprocity
            .or(scene.reciprocity)
            .unwrap_or(d.reciprocity),
        ..d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The afterglow (`--time`) is rendered by the camera path tracers only: every other
    /// method, asked for on the command line or by the scene, is refused with a message that
    /// says so, and a path tracer is accepted.
    #[test]
    fn afterglow_needs_a_camera_path_tracer() {
        let scene = |integrator: &str| {
            pt_scene::load_str(
                &format!(r#"<scene version="3.0.0">{integrator}<shape type="cube"/></scene>"#),
                std::path::Path::new("afterglow.xml"),
                std::path::Path::new("."),
                &[],
            )
            .unwrap()
            .integrator
        };
        let time = |kind: Option<IntegratorKind>| Overrides {
            kind,
            afterglow: Some(1.0),
            ..Overrides::default()
        };
        let refused = |d: &IntegratorDesc, o: &Overrides| match Integrator::from_desc(d, o) {
            Err(IntegratorError::Settings(m)) => m.contains("rendered by the path tracer"),
            _ => false,
        };
        let path = scene(r#"<integrator type="path"/>"#);
        assert!(matches!(
            Integrator::from_desc(&path, &time(None)),
            Ok(Integrator::Afterglow { .. })
        ));
        assert!(refused(&path, &time(Some(IntegratorKind::Bdpt))));
        assert!(refused(
            &path,
            &time(Some(IntegratorKind::PTracer {
                samples_per_pass: None
            }))
        ));
        assert!(refused(&scene(r#"<integrator type="bdpt"/>"#), &time(None)));
    }
}
