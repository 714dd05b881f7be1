//! `pt info`: what a scene contains, how the renderer reads it, and its colour mode.

use crate::{load_scene_with_summary, SceneArgs};
use anyhow::Result;
use clap::Args;
use pt_render::{BvhKind, LightSelection, Scene};
use pt_scene::Geometry;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args)]
pub(crate) struct InfoArgs {
    /// Mitsuba 3 XML scene or glTF 2.0 file (.gltf / .glb) [default: the built-in Cornell box].
    scene: Option<PathBuf>,
    #[command(flatten)]
    scene_args: SceneArgs,
}

/// One line describing a material for `pt info`: wrappers (twosided, mask, normalmap, blend)
/// as `name(parameters, inner)`, models by their parameters, textures by their plugin and
/// file.
fn describe_bsdf(kind: &pt_scene::BsdfKind) -> String {
    use pt_scene::BsdfKind as K;
    match kind {
        K::TwoSided { inner } => format!("twosided({})", describe_bsdf(&inner.kind)),
        K::Mask {
            opacity,
            cutoff,
            inner,
        } => {
            let cut = cutoff.map(|c| format!(", cutoff {c}")).unwrap_or_default();
            format!(
                "mask(opacity {opacity:?}{cut}, {})",
                describe_bsdf(&inner.kind)
            )
        }
        K::NormalMap {
            texture,
            scale,
            gltf,
            inner,
        } => format!(
            "normalmap({texture:?}, {} tangent space, scale {scale}, {})",
            if *gltf { "glTF" } else { "Mitsuba" },
            describe_bsdf(&inner.kind)
        ),
        K::BumpMap {
            height,
            scale,
            inner,
        } => format!(
            "bumpmap({height:?}, scale {scale}, {})",
            describe_bsdf(&inner.kind)
        ),
        K::Blend {
            weight,
            first,
            second,
        } => format!(
            "blend(weight {weight:?}, {} | {})",
            describe_bsdf(&first.kind),
            describe_bsdf(&second.kind)
        ),
        other => format!("{other:?}"),
    }
}

/// A light's intensity profile for `pt info`: its source, size and peak.
fn describe_profile(p: Option<&pt_scene::IntensityProfile>) -> String {
    use pt_scene::ProfileSource as S;
    match p.map(|p| (&p.source, p.scale)) {
        None => String::new(),
        Some((S::Ies(t), scale)) => format!(
            ", IES profile {} x {} angles, peak {} cd, scale {scale}",
            t.theta.len(),
            t.phi.len(),
            t.values.iter().fold(0.0f32, |m, &v| m.max(v))
        ),
        Some((S::Image(path), scale)) => {
            format!(", goniometric image {}, scale {scale}", path.display())
        }
    }
}

/// One line per light that is not on a shape: its plugin, where it is and what it emits.
fn describe_light(k: &pt_scene::LightKind) -> String {
    use pt_scene::LightKind as L;
    let at = |m: &pt_math::Mat4| m.transform_point3(pt_math::Vec3::ZERO);
    match k {
        L::Point {
            position,
            intensity,
            profile,
        } => format!(
            "point at {position:.3}, intensity {intensity:?}{}",
            describe_profile(profile.as_deref())
        ),
        L::Spot {
            to_world,
            intensity,
            cutoff_deg,
            beam_width_deg,
            texture,
            profile,
        } => format!(
            "spot at {:.3}, intensity {intensity:?}, cutoff {cutoff_deg} deg, beam {beam_width_deg} deg{}{}",
            at(to_world),
            texture
                .as_ref()
                .map(|t| format!(", texture {t:?}"))
                .unwrap_or_default(),
            describe_profile(profile.as_deref())
        ),
        L::Projector {
            to_world,
            irradiance,
            scale,
            projection,
        } => format!(
            "projector at {:.3}, irradiance {irradiance:?}, scale {scale}, {projection:?}",
            at(to_world)
        ),
        L::Directional {
            direction,
            irradiance,
        } => format!("directional towards {direction:.3}, irradiance {irradiance:?}"),
        L::Sun {
            direction,
            irradiance,
            angular_diameter_deg,
        } => format!("sun towards {direction:.3}, irradiance {irradiance:?}, diameter {angular_diameter_deg} deg"),
        L::Constant { radiance } => format!("constant, radiance {radiance:?}"),
        L::SunSky(s) => {
            let sun = s.to_world * s.sun_local;
            format!(
                "sunsky, sun towards {sun:.3} ({:.2} deg above the horizon), turbidity {}, albedo {:?}, sun x{}, sky x{}, aperture {} deg{}",
                s.sun_local.z.clamp(-1.0, 1.0).asin().to_degrees(),
                s.turbidity,
                s.albedo,
                s.sun_scale,
                s.sky_scale,
                s.sun_aperture_deg,
                if s.complex_sun { ", limb darkening" } else { "" }
            )
        }
        L::EnvMap {
            filename, scale, ..
        } => format!("envmap {}, scale {scale}", filename.display()),
    }
}

/// `pt info`: loads and builds the scene, then prints what it holds, section by section.
pub(crate) fn run(args: InfoArgs) -> Result<ExitCode> {
    let (desc, gltf_summary) = load_scene_with_summary(args.scene.as_deref(), &args.scene_args)?;
    let scene = Scene::build(&desc, BvhKind::Auto, LightSelection::Power)?;
    out!("scene       {}", desc.source.display());
    print_settings(&desc);
    print_shapes(&desc, &scene);
    print_materials_and_lights(&desc, &scene);
    if !gltf_summary.is_empty() {
        out!("glTF        (how the file maps onto the renderer; see pt-gltf's documentation)");
        for line in &gltf_summary {
            out!("  {line}");
        }
    }
    match desc.spectral_reason() {
        Some(why) => out!("mode        spectral, because {why}"),
        None => out!("mode        rgb (every input is RGB and no material depends on wavelength: RGB is exact)"),
    }
    Ok(ExitCode::SUCCESS)
}

/// The film, sampler, integrator (and its AOVs), camera and the camera's medium.
fn print_settings(desc: &pt_scene::SceneDesc) {
    out!(
        "film        {}x{}{}, filter {:?}, channels {}",
        desc.film.width,
        desc.film.height,
        desc.film.crop.map_or(String::new(), |c| format!(
            " (crop of a {}x{} film at {}, {})",
            c.film_size[0], c.film_size[1], c.offset[0], c.offset[1]
        )),
        desc.film.filter,
        desc.film.pixel_format.channels().join("")
    );
    out!(
        "sampler     {} {} spp, seed {}",
        desc.sampler.kind.plugin(),
        desc.sampler.sample_count,
        desc.sampler.seed
    );
    let i = &desc.integrator;
    out!(
        "integrator  {:?}, max_depth {}, rr_depth {}, hide_emitters {}{}{}",
        i.kind,
        i.max_depth,
        if i.rr_depth == u32::MAX {
            "none (no Russian roulette)".to_string()
        } else {
            i.rr_depth.to_string()
        },
        i.hide_emitters,
        if i.light_sampling {
            ""
        } else {
            ", BSDF sampling only"
        },
        match &i.moment {
            Some(name) => format!(" (moment: writes {name}.X/Y/Z and m2_{name}.X/Y/Z)"),
            None => String::new(),
        }
    );
    if let Some(aov) = &i.aov {
        out!(
            "aov         {}{}",
            aov.channel_names().join(" "),
            if aov.image.is_none() {
                " (no nested integrator: the image's channels are zero)"
            } else {
                ""
            }
        );
    }
    let c = &desc.camera;
    let pos = c.to_world.transform_point3(pt_math::Vec3::ZERO);
    let dir = c.to_world.transform_vector3(pt_math::Vec3::Z).normalize();
    out!(
        "camera      {:?}, at ({:.3}, {:.3}, {:.3}) looking ({:.3}, {:.3}, {:.3})",
        c.projection,
        pos.x,
        pos.y,
        pos.z,
        dir.x,
        dir.y,
        dir.z
    );
    if let Some(m) = &desc.camera_medium {
        out!("camera in   {}", medium_summary(m));
    }
}

/// The geometry's totals, then one line per shape and per shape group.
fn print_shapes(desc: &pt_scene::SceneDesc, scene: &Scene) {
    out!(
        "geometry    {} shapes{}, {} triangles{}, {} spheres, {} cylinders{}{}",
        desc.shapes.len(),
        if desc.instances.is_empty() {
            String::new()
        } else {
            format!(
                " and {} instances of {} shape groups (their primitives counted once)",
                desc.instances.len(),
                desc.groups.len()
            )
        },
        scene.stats.triangles,
        if scene.stats.parallelograms > 0 {
            format!(
                " ({} pairs tested as parallelograms)",
                scene.stats.parallelograms
            )
        } else {
            String::new()
        },
        scene.stats.spheres,
        scene.stats.cylinders,
        if scene.stats.curve_segments > 0 {
            format!(", {} curve segments", scene.stats.curve_segments)
        } else {
            String::new()
        },
        if scene.stats.degenerate_triangles > 0 {
            format!(
                " ({} zero-area triangles skipped)",
                scene.stats.degenerate_triangles
            )
        } else {
            String::new()
        }
    );
    for (k, s) in desc.shapes.iter().enumerate() {
        let geo = describe_geometry(&s.geometry);
        let bsdf = &desc.bsdfs[s.bsdf];
        out!(
            "  shape {k:<3} {:<10} {:<16} bsdf {:<12} {}{}",
            s.plugin,
            geo,
            bsdf.id.as_deref().unwrap_or("-"),
            s.emitter
                .as_ref()
                .map(|e| format!(
                    "emits {:?}{}",
                    e.radiance,
                    if e.primaries.is_some() {
                        " through display primaries"
                    } else {
                        ""
                    }
                ))
                .unwrap_or_default()
                + &[("interior", &s.interior), ("exterior", &s.exterior)]
                    .iter()
                    .filter_map(|(side, m)| m
                        .as_ref()
                        .map(|m| format!(" {side} {}", medium_summary(m))))
                    .collect::<String>(),
            s.id.as_deref()
                .map(|id| format!(" id={id}"))
                .unwrap_or_default(),
        );
    }
    for (gi, g) in desc.groups.iter().enumerate() {
        let uses = desc.instances.iter().filter(|i| i.group == gi).count();
        let triangles: usize = g
            .shapes
            .iter()
            .map(|s| match &s.geometry {
                Geometry::Mesh(m) => m.indices.len(),
                _ => 0,
            })
            .sum();
        out!(
            "  shapegroup {:<16} {} shapes ({} triangles), {} instance(s)",
            g.id,
            g.shapes.len(),
            triangles,
            uses
        );
    }
}

/// One line per material, then the lights: their count and one line per light of its own.
fn print_materials_and_lights(desc: &pt_scene::SceneDesc, scene: &Scene) {
    out!("materials   {}", desc.bsdfs.len());
    for b in &desc.bsdfs {
        out!(
            "  {:<12} {}",
            b.id.as_deref().unwrap_or("-"),
            describe_bsdf(&b.kind)
        );
    }
    let areas = scene
        .lights
        .iter()
        .filter(|l| matches!(l, pt_render::light::Light::Area(_)))
        .count();
    out!(
        "lights      {} ({areas} area light(s) on shapes, {} on their own)",
        scene.lights.len(),
        desc.lights.len()
    );
    for l in &desc.lights {
        out!("  {}", describe_light(&l.kind));
    }
}

/// A shape's geometry in a few words: its kind and size.
fn describe_geometry(geometry: &Geometry) -> String {
    match geometry {
        Geometry::Mesh(m) => format!("{} triangles", m.indices.len()),
        Geometry::Sphere { radius, .. } => format!("sphere r={radius}"),
        Geometry::Disk(d) => format!("disk, area {}", d.area()),
        Geometry::Cylinder { radius, length, .. } => {
            format!("cylinder r={radius} length={length}")
        }
        Geometry::Curves(c) => format!(
            "{} curve, {} control points, {} segments",
            match c.basis {
                pt_scene::CurveBasis::Linear => "linear",
                pt_scene::CurveBasis::BSpline => "B-spline",
            },
            c.points.len(),
            c.segments.len()
        ),
        Geometry::SdfGrid(g) => format!(
            "sdf grid {}x{}x{}, {} voxels on the surface, {} normals",
            g.resolution[0],
            g.resolution[1],
            g.resolution[2],
            g.occupied_voxels().count(),
            if g.smooth_normals {
                "smooth"
            } else {
                "analytic"
            }
        ),
    }
}

/// One line's worth of a medium: its kind, coefficients and phase function.
fn medium_summary(m: &pt_scene::MediumDesc) -> String {
    format!(
        "medium ({}) sigma_t {:?} albedo {:?} phase {:?}",
        if m.density.is_some() {
            "grid"
        } else {
            "homogeneous"
        },
        m.sigma_t,
        m.albedo,
        m.phase
    )
}
