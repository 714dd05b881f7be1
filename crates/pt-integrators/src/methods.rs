//! Each method's [`Integrator::render`]: build the scene, check that the method can render it,
//! sample (or solve), and report what was done in the [`Rendered`] image's summary and header.

use crate::{
    afterglow, aov, photonmap, ptracer, render_passes_saving, sppm, vcm, Integrator,
    IntegratorError, Job, PathSettings, PathTracer, RenderSettings, RenderState, Rendered, Run,
    Share,
};
use pt_radiosity::RadiosityParams;
use pt_render::{BvhKind, LightSelection, RenderOutput, Scene};
use pt_scene::SceneDesc;
use pt_spectrum::{srgb_to_xyz, ColorMode};
use std::time::{Duration, Instant};

impl Integrator {
    /// Renders the job. Path tracers honour `run.cancel` between passes and continue
    /// `run.resume`; radiosity runs to the end.
    pub fn render(&self, job: &Job, run: Run) -> Result<Rendered, IntegratorError> {
        if let (true, Some(why)) = (
            job.share != Share::WHOLE || run.checkpoint.is_some(),
            self.unshared_because(),
        ) {
            return Err(IntegratorError::Settings(format!(
                "{} cannot be split into parts or checkpointed: {why}",
                self.name()
            )));
        }
        match self {
            Integrator::Path(p) => render_path(self.name(), p, job.desc, job, run),
            Integrator::Direct(p) => render_path(self.name(), p, job.desc, job, run),
            Integrator::Afterglow { time, path } => {
                let start = Instant::now();
                let dark = afterglow::afterglow(job.desc, *time, job.seed)?;
                let mut r = render_path("afterglow", path, &dark, job, run)?;
                r.build_time += start.elapsed();
                r.header.push(("afterglow_time_s".into(), time.to_string()));
                Ok(r)
            }
            Integrator::PTracer {
                settings,
                samples_per_pass,
            } => render_ptracer(settings, *samples_per_pass, job, run),
            Integrator::Sppm { settings, sppm } => render_sppm(settings, sppm, job, run),
            Integrator::Vcm { settings, vcm } => render_vcm(settings, vcm, job, run),
            Integrator::PhotonMapper { settings, photons } => {
                render_photonmapper(settings, photons, job, run)
            }
            Integrator::Radiosity(params) => render_radiosity(params, job, run),
            Integrator::Depth => render_depth(job, run),
        }
    }
}

/// The light tracer over the image in passes of batches of light paths
/// ([`ptracer::render_light_passes`]).
fn render_ptracer(
    path: &PathSettings,
    samples_per_pass: Option<u32>,
    job: &Job,
    run: Run,
) -> Result<Rendered, IntegratorError> {
    if let Some(n) = samples_per_pass {
        if job.spp % n.min(job.spp.max(1)) != 0 {
            return Err(IntegratorError::Settings(format!(
                "ptracer: the sample count ({}) must be a multiple of samples_per_pass ({n})",
                job.spp
            )));
        }
    }
    let (scene, settings, build_time, mut state) = prepare(
        job,
        path,
        run.resume,
        |s| s.light.is_some(),
        "the saved state is a path tracer's, not a light tracer's",
        RenderState::for_light_paths,
        |scene, settings| {
            refuse_glowing_media(scene)
                .and_then(|_| refuse_meters("ptracer", scene))
                .and_then(|_| ptracer::check(settings))
        },
    )?;
    let paths_per_batch = u64::from(settings.width) * u64::from(settings.height);
    run.progress.start_samples(
        paths_per_batch * u64::from(settings.spp),
        paths_per_batch * u64::from(state.spp_done),
    );
    let complete = ptracer::render_light_passes(
        &scene,
        &settings,
        &mut state,
        run.cancel,
        run.checkpoint.as_ref(),
        &|n| run.progress.samples(n),
    );
    let output = state.output();
    let (summary, warnings) = report(
        "ptracer",
        "a sample being one light path; ",
        &output,
        build_time,
    );
    let header = vec![
        ("integrator".to_string(), "ptracer".to_string()),
        ("max_depth".to_string(), path.max_depth.to_string()),
    ];
    Ok(Rendered {
        output,
        mode: scene.mode,
        header,
        summary,
        warnings,
        state: Some(state),
        complete,
        build_time,
        extra_channels: Vec::new(),
    })
}

/// The log line every sampling method ends with (size, samples per pixel, time, rate, scene
/// build; `what` says what a sample is where it is not a camera path) and the warning about
/// samples left out as NaN or infinite.
fn report(
    name: &str,
    what: &str,
    output: &RenderOutput,
    build_time: Duration,
) -> (String, Vec<String>) {
    let secs = output.time.as_secs_f64();
    let samples = u64::from(output.width) * u64::from(output.height) * u64::from(output.spp);
    let summary = format!(
        "{name}: {}x{} at {} spp in {:.2} s ({:.2} M samples/s, {what}scene build {:.2} s)",
        output.width,
        output.height,
        output.spp,
        secs,
        samples as f64 / secs.max(1e-9) / 1e6,
        build_time.as_secs_f64()
    );
    let mut warnings = Vec::new();
    if output.nonfinite_samples > 0 {
        warnings.push(format!(
            "{} samples were NaN or infinite and were left out of the image",
            output.nonfinite_samples
        ));
    }
    (summary, warnings)
}

/// The path tracer over the image in passes (see [`crate::render_passes`]).
fn render_path(
    name: &str,
    p: &PathTracer,
    desc: &SceneDesc,
    job: &Job,
    run: Run,
) -> Result<Rendered, IntegratorError> {
    let build_start = Instant::now();
    let scene = Scene::build_with_mode(desc, job.bvh, job.selection, job.mode)?;
    let build_time = build_start.elapsed();
    let settings = RenderSettings {
        spp: job.share.samples_of(job.spp),
        seed: job.seed,
        path: p.settings,
        clamp: p.clamp,
        share: job.share,
        variance: job.variance,
        ..RenderSettings::from_desc(desc)
    };
    let mut state = match run.resume {
        Some(s) => s,
        None => RenderState::new(&settings),
    };
    if state.spp_done > settings.spp {
        return Err(IntegratorError::Settings(format!(
            "the saved render already has {} spp, more than --spp {}",
            state.spp_done, settings.spp
        )));
    }
    let pixels = u64::from(settings.width) * u64::from(settings.height);
    let aov = desc.integrator.aov.as_ref();
    // An `aov` integrator without a nested one renders no image (its channels stay zero).
    let complete = if aov.is_some_and(|a| a.image.is_none()) {
        true
    } else {
        run.progress.start_samples(
            pixels * u64::from(settings.spp),
            pixels * u64::from(state.spp_done),
        );
        render_passes_saving(
            &scene,
            &settings,
            &mut state,
            run.cancel,
            run.checkpoint.as_ref(),
            &|n| run.progress.samples(n),
        )
    };
    let output = state.output();
    let mut extra_channels = Vec::new();
    // A share's AOVs are rendered when the shares are merged (their passes are not split).
    if let (Some(aov), true, true) = (aov, complete, job.share == Share::WHOLE) {
        let mut planes: Vec<Vec<f32>> = Vec::new();
        if aov.image.is_some() {
            planes.extend((0..3).map(|c| output.mean.iter().map(|p| p[c]).collect()));
            planes.push(output.alpha.clone().unwrap_or_default());
        }
        planes.extend(aov::render_aovs(&scene, &settings, aov));
        extra_channels = aov.channel_names().into_iter().zip(planes).collect();
    }
    if let (Some(name), Some(m2)) = (&desc.integrator.moment, &output.second_moment) {
        let xyz: Vec<[f32; 3]> = output.mean.iter().map(|&c| srgb_to_xyz(c)).collect();
        for (prefix, values) in [(name.clone(), &xyz), (format!("m2_{name}"), m2)] {
            for (c, axis) in ["X", "Y", "Z"].iter().enumerate() {
                let plane = values.iter().map(|v| v[c]).collect();
                extra_channels.push((format!("{prefix}.{axis}"), plane));
            }
        }
    }
    let (summary, warnings) = report(name, "", &output, build_time);
    let mut header = vec![
        ("integrator".to_string(), name.to_string()),
        ("max_depth".to_string(), p.settings.max_depth.to_string()),
        (
            "strategy".to_string(),
            format!("{:?}", p.settings.strategy).to_lowercase(),
        ),
    ];
    if let Some(c) = p.clamp {
        header.push(("clamp".into(), c.to_string()));
    }
    Ok(Rendered {
        output,
        mode: scene.mode,
        header,
        summary,
        warnings,
        state: Some(state),
        complete,
        build_time,
        extra_channels,
    })
}

/// Stochastic progressive photon mapping ([`sppm::render_sppm_passes`]).
fn render_sppm(
    path: &PathSettings,
    params: &sppm::SppmSettings,
    job: &Job,
    run: Run,
) -> Result<Rendered, IntegratorError> {
    let (scene, settings, build_time, mut state) = prepare(
        job,
        path,
        run.resume,
        |s| s.light.is_none() && s.splat.is_none(),
        "the saved state is not a photon mapper's",
        sppm::new_state,
        |scene, _| refuse_media("sppm", scene).and_then(|_| sppm::check(params)),
    )?;
    let pixels = u64::from(settings.width) * u64::from(settings.height);
    run.progress.start_samples(
        pixels * u64::from(settings.spp),
        pixels * u64::from(state.spp_done),
    );
    let complete =
        sppm::render_sppm_passes(&scene, &settings, params, &mut state, run.cancel, &|n| {
            run.progress.samples(n)
        });
    let mut output = state.output();
    output.alpha = None;
    let photons = params.photons.unwrap_or(pixels);
    let what =
        format!("a sample being an iteration's camera path, {photons} photons per iteration; ");
    let (summary, warnings) = report("sppm", &what, &output, build_time);
    let header = vec![
        ("integrator".to_string(), "sppm".to_string()),
        ("max_depth".to_string(), path.max_depth.to_string()),
        ("photons_per_iteration".to_string(), photons.to_string()),
        ("alpha".to_string(), params.alpha.to_string()),
    ];
    Ok(Rendered {
        output,
        mode: scene.mode,
        header,
        summary,
        warnings,
        state: Some(state),
        complete,
        build_time,
        extra_channels: Vec::new(),
    })
}

/// The refusal of the light-side methods that do not trace participating media (all but
/// `ptracer`).
fn refuse_media(name: &str, scene: &Scene) -> Result<(), String> {
    if let Some(m) = scene.media.first() {
        return Err(format!(
            "{}: {name} does not yet trace participating media (not yet implemented): the scene has {} medium(s); render it with volpath or ptracer",
            m.loc,
            scene.media.len()
        ));
    }
    Ok(())
}

/// The refusal of the methods that connect light paths to the camera when the sensor is a
/// radiancemeter (one ray, which a connection meets with probability zero), an
/// irradiancemeter, a distant sensor or a batch (whose importance pt does not evaluate).
pub(crate) fn refuse_meters(name: &str, scene: &Scene) -> Result<(), String> {
    if scene.camera.refuses_light_paths() {
        return Err(format!(
            "{}: {name} cannot render for a radiancemeter, irradiancemeter, distant or batch sensor (light paths do not connect to them); use path or volpath",
            scene.camera.loc()
        ));
    }
    Ok(())
}

/// The light tracer's refusal of glowing media: it starts paths on the lights only, and a
/// medium's emission (a pt extension) is not one of them.
fn refuse_glowing_media(scene: &Scene) -> Result<(), String> {
    if let Some(m) = scene.media.iter().find(|m| m.emission.is_some()) {
        return Err(format!(
            "{}: ptracer does not start light paths in glowing media (a medium with emission is not yet a light source; not yet implemented): render the scene with volpath",
            m.loc
        ));
    }
    Ok(())
}

/// What every sampling method does before it samples: builds the scene and the render
/// settings (the job's spp and seed, `path`), runs the method's `check`, and takes the saved
/// state to continue (refused with `wrong` unless `accepts` it, or holding more samples than
/// asked for) or a `new` one.
#[allow(clippy::type_complexity)]
#[allow(clippy::too_many_arguments)]
fn prepare(
    job: &Job,
    path: &PathSettings,
    resume: Option<RenderState>,
    accepts: impl Fn(&RenderState) -> bool,
    wrong: &str,
    new: impl Fn(&RenderSettings) -> RenderState,
    check: impl Fn(&Scene, &RenderSettings) -> Result<(), String>,
) -> Result<(Scene, RenderSettings, Duration, RenderState), IntegratorError> {
    let desc = job.desc;
    let build_start = Instant::now();
    let scene = Scene::build_with_mode(desc, job.bvh, job.selection, job.mode)?;
    let build_time = build_start.elapsed();
    let settings = RenderSettings {
        spp: job.share.samples_of(job.spp),
        seed: job.seed,
        path: *path,
        share: job.share,
        variance: job.variance,
        ..RenderSettings::from_desc(desc)
    };
    check(&scene, &settings).map_err(IntegratorError::Settings)?;
    let state = match resume {
        Some(s) if accepts(&s) => s,
        Some(_) => return Err(IntegratorError::Settings(wrong.into())),
        None => new(&settings),
    };
    if state.spp_done > settings.spp {
        return Err(IntegratorError::Settings(format!(
            "the saved render already has {} spp, more than --spp {}",
            state.spp_done, settings.spp
        )));
    }
    Ok((scene, settings, build_time, state))
}

/// Photon mapping ([`photonmap::render_photon_passes`]).
fn render_photonmapper(
    path: &PathSettings,
    params: &photonmap::PhotonMapSettings,
    job: &Job,
    run: Run,
) -> Result<Rendered, IntegratorError> {
    let (scene, settings, build_time, mut state) = prepare(
        job,
        path,
        run.resume,
        |s| s.light.is_none() && s.splat.is_none(),
        "the saved state is not a photon mapper's",
        sppm::new_state,
        |scene, _| refuse_media("photonmapper", scene).and_then(|_| photonmap::check(params)),
    )?;
    let pixels = u64::from(settings.width) * u64::from(settings.height);
    run.progress.start_samples(
        pixels * u64::from(settings.spp),
        pixels * u64::from(state.spp_done),
    );
    let complete = photonmap::render_photon_passes(
        &scene,
        &settings,
        params,
        &mut state,
        run.cancel,
        run.checkpoint.as_ref(),
        &|n| run.progress.samples(n),
    );
    let mut output = state.output();
    output.alpha = None;
    let what = format!(
        "a sample being an iteration's camera path, {} + {} photons per iteration; ",
        params.global_photons, params.caustic_photons
    );
    let (summary, warnings) = report("photonmapper", &what, &output, build_time);
    let header = vec![
        ("integrator".to_string(), "photonmapper".to_string()),
        ("max_depth".to_string(), path.max_depth.to_string()),
        (
            "global_photons".to_string(),
            params.global_photons.to_string(),
        ),
        (
            "caustic_photons".to_string(),
            params.caustic_photons.to_string(),
        ),
        ("lookup_size".to_string(), params.lookup.to_string()),
        ("final_gather".to_string(), params.final_gather.to_string()),
    ];
    Ok(Rendered {
        output,
        mode: scene.mode,
        header,
        summary,
        warnings,
        state: Some(state),
        complete,
        build_time,
        extra_channels: Vec::new(),
    })
}

/// Bidirectional path tracing and vertex connection and merging
/// ([`vcm::render_vcm_passes`]).
fn render_vcm(
    path: &PathSettings,
    params: &vcm::VcmSettings,
    job: &Job,
    run: Run,
) -> Result<Rendered, IntegratorError> {
    let name = params.name();
    let (scene, settings, build_time, mut state) = prepare(
        job,
        path,
        run.resume,
        |s| s.light.is_some(),
        "the saved state is not a bidirectional render's (a light film)",
        RenderState::for_light_paths,
        |scene, settings| {
            refuse_media(params.name(), scene).and_then(|_| vcm::check(scene, settings, params))
        },
    )?;
    let pixels = u64::from(settings.width) * u64::from(settings.height);
    run.progress.start_samples(
        pixels * u64::from(settings.spp),
        pixels * u64::from(state.spp_done),
    );
    let complete = vcm::render_vcm_passes(
        &scene,
        &settings,
        params,
        &mut state,
        run.cancel,
        run.checkpoint.as_ref(),
        &|n| run.progress.samples(n),
    );
    let output = state.output();
    let what = "a sample being a camera and a light subpath per pixel; ";
    let (summary, warnings) = report(name, what, &output, build_time);
    let mut header = vec![
        ("integrator".to_string(), name.to_string()),
        ("max_depth".to_string(), path.max_depth.to_string()),
    ];
    if params.merging {
        header.push((
            "initial_radius".to_string(),
            params.radius(0, scene.bounds.1).to_string(),
        ));
        header.push(("alpha".to_string(), params.alpha.to_string()));
    }
    Ok(Rendered {
        output,
        mode: scene.mode,
        header,
        summary,
        warnings,
        state: Some(state),
        complete,
        build_time,
        extra_channels: Vec::new(),
    })
}

/// Mitsuba's `depth` integrator ([`aov::render_depth`]): the distance to the first hit as the
/// image, in one pass (not resumable or split into parts).
fn render_depth(job: &Job, run: Run) -> Result<Rendered, IntegratorError> {
    if run.resume.is_some() {
        return Err(IntegratorError::Settings(
            "--resume applies to the path tracers, not to depth".into(),
        ));
    }
    let build_start = Instant::now();
    let scene = Scene::build_with_mode(job.desc, job.bvh, job.selection, job.mode)?;
    let build_time = build_start.elapsed();
    let settings = RenderSettings {
        spp: job.spp,
        seed: job.seed,
        ..RenderSettings::from_desc(job.desc)
    };
    let start = Instant::now();
    run.progress.stage("depth", 0.0);
    let (depth, variance, alpha) = aov::render_depth(&scene, &settings);
    run.progress.stage("depth", 1.0);
    let output = RenderOutput {
        width: settings.width,
        height: settings.height,
        mean: depth.iter().map(|&t| [t; 3]).collect(),
        variance: variance.iter().map(|&v| [v; 3]).collect(),
        spp: settings.spp,
        time: start.elapsed(),
        nonfinite_samples: 0,
        alpha: Some(alpha),
        second_moment: None,
    };
    let (summary, warnings) = report("depth", "", &output, build_time);
    Ok(Rendered {
        output,
        mode: scene.mode,
        header: vec![("integrator".into(), "depth".into())],
        summary,
        warnings,
        state: None,
        complete: true,
        build_time,
        extra_channels: Vec::new(),
    })
}

/// Radiosity: meshing, form factors, solve, display (crate `pt-radiosity`).
fn render_radiosity(
    params: &RadiosityParams,
    job: &Job,
    run: Run,
) -> Result<Rendered, IntegratorError> {
    if run.resume.is_some() {
        return Err(IntegratorError::Settings(
            "--resume applies to the path tracer, not to radiosity".into(),
        ));
    }
    if job.mode.is_some() || job.selection != LightSelection::default() || job.bvh != BvhKind::Auto
    {
        return Err(IntegratorError::Settings(
            "--mode, --light-selection and --bvh apply to the path tracer, not to radiosity".into(),
        ));
    }
    let p = RadiosityParams {
        spp: job.spp,
        seed: job.seed,
        ..params.clone()
    };
    let (output, stats) =
        pt_radiosity::render(job.desc, &p, &|stage, f| run.progress.stage(stage, f))?;
    let summary = format!(
        "radiosity: {} patches (size {:.4}), {} form factors ({:.1} MB), form factors {:.2} s, solve {:.2} s in {} iterations, total {:.2} s",
        stats.patches,
        stats.patch_size,
        stats.nnz,
        stats.memory_bytes as f64 / 1e6,
        stats.form_factor_time.as_secs_f64(),
        stats.solve_time.as_secs_f64(),
        stats.iterations,
        output.time.as_secs_f64(),
    );
    let header = vec![
        ("integrator".into(), "radiosity".into()),
        ("patches".into(), stats.patches.to_string()),
        ("rays_per_patch".into(), p.rays_per_patch.to_string()),
        ("solver".into(), format!("{:?}", p.solver).to_lowercase()),
        ("display".into(), format!("{:?}", p.display).to_lowercase()),
        ("iterations".into(), stats.iterations.to_string()),
    ];
    let mode = if job.desc.spectral_reason().is_some() {
        ColorMode::Spectral
    } else {
        ColorMode::Rgb
    };
    Ok(Rendered {
        output,
        mode,
        header,
        summary,
        warnings: stats.warnings.clone(),
        state: None,
        complete: true,
        build_time: Duration::ZERO,
        extra_channels: Vec::new(),
    })
}
