//! The four studies: their scenes (embedded from `scenes/atlas/`), regions and texts.

use super::{
    budget_words, check, load, mean_bias, rect, reference, region_error, render_steps,
    render_within, three_strategies, with_strategy, AtlasSettings, Budget, Equal, Panel, Reference,
    Study, SEED, STRATEGIES,
};
use crate::{LabError, Result};
use pt_integrators::{RenderSettings, Strategy};
use pt_render::{RenderOutput, Scene};
use std::path::Path;
use std::sync::atomic::AtomicBool;

/// The Veach atlas scene (see the module doc).
pub(super) const VEACH: &str = include_str!("../../../../scenes/atlas/veach-mis.xml");
/// Plate roughness (GGX alpha), top to bottom, as in the scene file.
const PLATE_ALPHA: [f32; 4] = [0.005, 0.03, 0.1, 0.3];
/// Plate centre heights and tilt angles (degrees), as in the scene file.
const PLATE_Y: [f32; 4] = [1.5, 0.5, -0.5, -1.5];
const PLATE_TILT_DEG: [f32; 4] = [-4.412, -10.383, -16.11, -21.52];
/// Light radii, left to right, as in the scene file.
const LIGHT_RADIUS: [f32; 4] = [0.03, 0.1, 0.3, 0.9];
/// Column bands in world x on the plates: midway between the highlights of neighbouring
/// lights (the mirror image of a light at x_l from the camera at z = 10 with lights at z = 8
/// lies near x = x_l * 10 / 18, so the boundaries are at 0 and +-1.11).
const BANDS_X: [f32; 5] = [-4.0, -1.11, 0.0, 1.11, 4.0];

/// The caustic scenes, one per light radius (scene units), at equal power.
pub const CAUSTIC: [(&str, f32, &str); 5] = [
    (
        "caustic-r0.01",
        0.01,
        include_str!("../../../../scenes/atlas/caustic-r0.01.xml"),
    ),
    (
        "caustic-r0.03",
        0.03,
        include_str!("../../../../scenes/atlas/caustic-r0.03.xml"),
    ),
    (
        "caustic-r0.1",
        0.1,
        include_str!("../../../../scenes/atlas/caustic-r0.1.xml"),
    ),
    (
        "caustic-r0.3",
        0.3,
        include_str!("../../../../scenes/atlas/caustic-r0.3.xml"),
    ),
    (
        "caustic-r1",
        1.0,
        include_str!("../../../../scenes/atlas/caustic-r1.xml"),
    ),
];
/// The caustic region as fractions of the image (row0, row1, col0, col1; half-open): rows
/// 40..51 and columns 52..74 of the 96 x 64 image, which hold the focused spot for every light
/// size (read off the Mitsuba references: the spot of the 0.01 light is pixel (64, 45), that of
/// the radius-1 light spreads over about 10 x 20 pixels around it, inside the sphere's shadow).
const CAUSTIC_FRAC: (f32, f32, f32, f32) = (40.0 / 64.0, 51.0 / 64.0, 52.0 / 96.0, 74.0 / 96.0);

/// The radiosity atlas scene.
const RADIOSITY: &str = include_str!("../../../../scenes/atlas/radiosity-glossy.xml");
/// Back-wall strips, left to right: `None` is the diffuse control, else the GGX alpha.
const STRIP_ALPHA: [Option<f32>; 6] = [
    None,
    Some(0.5),
    Some(0.2),
    Some(0.08),
    Some(0.03),
    Some(0.01),
];
/// Radiosity settings of the study: patches of edge 0.2 (about 3,400 triangles on the box),
/// 256 rays per patch (form-factor noise ~1/sqrt(256 F), a few % for the ceiling seen from a
/// wall patch), smoothed display; a few seconds on two cores.
const RADIOSITY_PATCH: f32 = 0.2;
const RADIOSITY_RAYS: u32 = 256;

/// Pixel rectangles (row0, row1, col0, col1; half-open) of the plate x light regions, from the
/// camera of the Veach scene (at z = 10 looking down -z, horizontal fov 46 degrees): a world
/// point (x, y, z) projects to column `W/2 + f x / (10 - z)` and row `H/2 - f y / (10 - z)`,
/// `f = (W/2) / tan(23 deg)`. One pixel is trimmed at each edge so that the plate borders
/// (partly background) stay out.
fn veach_regions(w: u32, h: u32) -> [[(u32, u32, u32, u32); 4]; 4] {
    let f = (w as f32 / 2.0) / 23f32.to_radians().tan();
    let row = |y: f32, z: f32| {
        (h as f32 / 2.0 - f * y / (10.0 - z))
            .round()
            .clamp(0.0, h as f32) as u32
    };
    let col = |x: f32| (w as f32 / 2.0 + f * x / 10.0).round().clamp(0.0, w as f32) as u32;
    let mut out = [[(0, 0, 0, 0); 4]; 4];
    for p in 0..4 {
        let a = PLATE_TILT_DEG[p].to_radians();
        // Rotation about x by a maps (0, +-0.4, 0) to (0, +-0.4 cos a, +-0.4 sin a).
        let (top, bottom) = (
            row(PLATE_Y[p] + 0.4 * a.cos(), 0.4 * a.sin()),
            row(PLATE_Y[p] - 0.4 * a.cos(), -0.4 * a.sin()),
        );
        for l in 0..4 {
            out[p][l] = (
                top + 1,
                bottom.saturating_sub(1),
                col(BANDS_X[l]) + 1,
                col(BANDS_X[l + 1]).saturating_sub(1),
            );
        }
    }
    out
}

/// The Veach study (on the current rayon pool).
pub fn veach(o: &AtlasSettings) -> Result<Study> {
    check(o)?;
    let (scene, base, _) = load(VEACH, "veach-mis", o.shrink)?;
    let reference = reference(&o.references, "veach-mis", &scene, &base, o.fallback_spp)?;
    let regs = veach_regions(base.width, base.height);
    let outs = three_strategies(&scene, &base, o);
    let mut panels = Vec::new();
    let mut ref_noise = vec![vec![0.0; 4]; 4];
    for ((name, _), out) in STRATEGIES.iter().zip(&outs) {
        let mut cells = vec![vec![0.0; 4]; 4];
        for p in 0..4 {
            for l in 0..4 {
                let (e, n) = region_error(&out.mean, &reference, &rect(base.width, regs[p][l]));
                cells[p][l] = e;
                ref_noise[p][l] = n;
            }
        }
        panels.push(Panel {
            name: name.to_string(),
            cells,
            spp: vec![out.spp; 4],
            secs: vec![out.time.as_secs_f64(); 4],
        });
    }
    let text = format!(
        "Scene `scenes/atlas/veach-mis.xml` (in the style of Veach 1997, thesis fig. 9.2, written for this project): \
         plates of GGX roughness {PLATE_ALPHA:?} (rows, top to bottom) lit by spherical lights of radius {LIGHT_RADIUS:?} \
         and equal power (columns, left to right), direct light only, {}x{} pixels. Budget: {}. Reference: {}. \
         Error: relative RMSE of luminance per plate x light region. Expected (Veach's result): BSDF sampling fails on \
         rough plates under small lights (a sampled direction rarely hits the light), light sampling on smooth plates \
         under large lights (a point on the light rarely lies in the narrow lobe), MIS is never much worse than the \
         better of the two.",
        base.width,
        base.height,
        budget_words(o),
        reference.source
    );
    Ok(Study {
        key: "veach",
        title: "Direct light: BSDF sampling, light sampling and MIS (Veach)".into(),
        row_label: "plate alpha".into(),
        col_label: "light radius".into(),
        rows: PLATE_ALPHA.iter().map(|a| a.to_string()).collect(),
        cols: LIGHT_RADIUS.iter().map(|r| r.to_string()).collect(),
        panels,
        ref_noise,
        text,
    })
}

/// The caustic and rest regions of a `w x h` caustic image.
fn caustic_regions(w: u32, h: u32) -> [Vec<usize>; 2] {
    let (r0, r1, c0, c1) = CAUSTIC_FRAC;
    let r = (
        (r0 * h as f32).round() as u32,
        (r1 * h as f32).round() as u32,
        (c0 * w as f32).round() as u32,
        (c1 * w as f32).round() as u32,
    );
    let caustic = rect(w, r);
    let inside: std::collections::HashSet<usize> = caustic.iter().copied().collect();
    let rest = (0..(w * h) as usize)
        .filter(|i| !inside.contains(i))
        .collect();
    [caustic, rest]
}

/// The caustic study (on the current rayon pool). `radii` selects scenes of [`CAUSTIC`] by index.
pub fn caustic(o: &AtlasSettings, radii: &[usize]) -> Result<Study> {
    check(o)?;
    if let Some(k) = radii.iter().find(|&&k| k >= CAUSTIC.len()) {
        return Err(LabError::Invalid(format!(
            "caustic: no light radius {k} (there are {})",
            CAUSTIC.len()
        )));
    }
    let mut panels = Panel::empty(STRATEGIES.iter().map(|(n, _)| *n), 2);
    let mut ref_noise = vec![Vec::new(), Vec::new()];
    let mut sources = Vec::new();
    let mut size = (0, 0);
    for &k in radii {
        let (name, _, xml) = CAUSTIC[k];
        let (scene, base, _) = load(xml, name, o.shrink)?;
        size = (base.width, base.height);
        let reference = reference(&o.references, name, &scene, &base, o.fallback_spp)?;
        sources.push(reference.source.clone());
        let regions = caustic_regions(base.width, base.height);
        let outs = three_strategies(&scene, &base, o);
        for (panel, out) in panels.iter_mut().zip(&outs) {
            for (g, pixels) in regions.iter().enumerate() {
                let (e, n) = region_error(&out.mean, &reference, pixels);
                panel.cells[g].push(e);
                if panel.name == "MIS" {
                    ref_noise[g].push(n);
                }
            }
            panel.spp.push(out.spp);
            panel.secs.push(out.time.as_secs_f64());
        }
    }
    let all_mitsuba = sources.iter().all(|s| s.starts_with("Mitsuba"));
    let text = format!(
        "Scenes `scenes/atlas/caustic-r*.xml` (written for this project): a glass sphere (ior 1.5) on a diffuse floor \
         under one spherical light of radius 0.01 to 1 (columns) at equal power, {}x{} pixels, max_depth 8. The \
         caustic region is a fixed rectangle around the focused spot (rows {:.0}-{:.0}%, columns {:.0}-{:.0}% of the \
         image), the rest is every other pixel (floor, shadow, sphere). Budget: {} (per scene). References: {}. \
         The caustic is reached only by paths that leave the floor by BSDF sampling and cross the glass: next-event \
         estimation from the floor is blocked by the sphere, and after the glass (a delta BSDF) light sampling cannot \
         be used, so every strategy, light sampling and MIS included, finds the caustic only when a cosine-sampled \
         direction happens to pass through the lens onto the light (pt, like Mitsuba, counts emission after a delta \
         bounce in every strategy). That chance falls with the light's solid angle, so the caustic's error grows \
         as the light shrinks at equal power. An error of exactly 100% means that no sample found the caustic: \
         the image has none of it. The rest region holds the sphere's shadow, into which the ball lens's \
         spherical aberration spreads a halo of the same caustic light, found the same rare way.",
        size.0,
        size.1,
        100.0 * CAUSTIC_FRAC.0,
        100.0 * CAUSTIC_FRAC.1,
        100.0 * CAUSTIC_FRAC.2,
        100.0 * CAUSTIC_FRAC.3,
        budget_words(o),
        if all_mitsuba { format!("Mitsuba 3 (`{}/caustic-r*.exr`)", o.references.display()) } else { sources.join("; ") }
    );
    Ok(Study {
        key: "caustic",
        title: "Caustics from small lights: a glass sphere under lights of radius 0.01 to 1".into(),
        row_label: "region".into(),
        col_label: "light radius".into(),
        rows: vec!["caustic".into(), "rest".into()],
        cols: radii.iter().map(|&k| CAUSTIC[k].1.to_string()).collect(),
        panels,
        ref_noise,
        text,
    })
}

/// Pixel regions of the radiosity scene: the six back-wall strips, then everything else
/// ("walls"). The back wall is at z = -1, the camera at z = 0.99 looking down -z with a
/// horizontal fov of 70 degrees: a point (x, y, -1) projects to column `W/2 + f x / 1.99` and
/// row `H/2 - f y / 1.99`, `f = (W/2) / tan(35 deg)`; one pixel is trimmed at each strip edge.
fn radiosity_regions(w: u32, h: u32) -> Vec<Vec<usize>> {
    let f = (w as f32 / 2.0) / 35f32.to_radians().tan();
    let col = |x: f32| (w as f32 / 2.0 + f * x / 1.99).round().clamp(0.0, w as f32) as u32;
    let row = |y: f32| (h as f32 / 2.0 - f * y / 1.99).round().clamp(0.0, h as f32) as u32;
    let mut out: Vec<Vec<usize>> = (0..6)
        .map(|i| {
            let (x0, x1) = (-1.0 + i as f32 / 3.0, -1.0 + (i + 1) as f32 / 3.0);
            rect(
                w,
                (
                    row(1.0) + 1,
                    row(-1.0).saturating_sub(1),
                    col(x0) + 1,
                    col(x1).saturating_sub(1),
                ),
            )
        })
        .collect();
    let (c0, c1, r0, r1) = (col(-1.0), col(1.0), row(1.0), row(-1.0));
    let walls = (0..(w * h) as usize).filter(|&i| {
        let (x, y) = (i as u32 % w, i as u32 / w);
        !(x >= c0 && x < c1 && y >= r0 && y < r1)
    });
    out.push(walls.collect());
    out
}

/// The radiosity study (on the current rayon pool).
pub fn radiosity(o: &AtlasSettings) -> Result<Study> {
    check(o)?;
    let (scene, base, desc) = load(RADIOSITY, "radiosity-glossy", o.shrink)?;
    let reference = reference(
        &o.references,
        "radiosity-glossy",
        &scene,
        &base,
        o.fallback_spp,
    )?;
    let regions = radiosity_regions(base.width, base.height);
    let params = pt_radiosity::RadiosityParams {
        patch_size: Some(RADIOSITY_PATCH * o.shrink as f32),
        rays_per_patch: RADIOSITY_RAYS / o.shrink,
        seed: SEED,
        ..Default::default()
    };
    let (rad, stats) = pt_radiosity::render(&desc, &params, &|_, _| {})
        .map_err(|e| LabError::from(e).context("radiosity"))?;
    let budget = match o.equal {
        Equal::Time => Budget::Time(rad.time),
        Equal::Spp => Budget::Spp(o.spp),
    };
    let path = render_within(&scene, &with_strategy(&base, Strategy::Mis), budget);
    let n = regions.len();
    let mut panels = Vec::new();
    let mut ref_noise = vec![vec![f64::NAN; n]; 2];
    for (name, out) in [("radiosity", &rad), ("path tracing (MIS)", &path)] {
        let mut cells = vec![vec![0.0; n]; 2];
        for (g, pixels) in regions.iter().enumerate() {
            let (e, noise) = region_error(&out.mean, &reference, pixels);
            cells[0][g] = e;
            cells[1][g] = mean_bias(&out.mean, &reference, pixels).abs();
            ref_noise[0][g] = noise;
        }
        panels.push(Panel {
            name: name.to_string(),
            cells,
            spp: vec![out.spp; n],
            secs: vec![out.time.as_secs_f64(); n],
        });
    }
    let warning = stats
        .warnings
        .first()
        .map(|w| w.split(": ").last().unwrap_or(w).to_string())
        .unwrap_or_default();
    let text = format!(
        "Scene `scenes/atlas/radiosity-glossy.xml` (written for this project): a closed box lit by its whole ceiling, \
         {}x{} pixels; the back wall is six strips, left to right a diffuse 0.5 control and GGX conductors of alpha \
         0.5, 0.2, 0.08, 0.03 and 0.01 whose specular reflectance makes their albedo 0.5 at 15 degrees. pt-radiosity \
         represents only diffuse surfaces: it treats every other material as grey diffuse 0.5 and warns (\"{}\"; {} \
         warnings here), so the strips get the right albedo and lose only their view dependence. Radiosity: patch \
         size {}, {} rays per patch, smoothed display, {} patches, {:.2} s in all. Path tracing: MIS, {}. Reference: \
         {}. Rows: relative RMSE of luminance per region, and |bias of the region's mean luminance|. With the albedo \
         matched the glossy strips' means are still off, because a glossy strip returns the radiance of the part of \
         the box its lobe sees, not the cosine-weighted average a diffuse surface of the same albedo returns.",
        base.width,
        base.height,
        warning,
        stats.warnings.len(),
        params.patch_size.unwrap_or(0.0),
        params.rays_per_patch,
        stats.patches,
        rad.time.as_secs_f64(),
        match o.equal {
            Equal::Time => "at the radiosity run's wall time".to_string(),
            Equal::Spp => format!("{} spp", o.spp),
        },
        reference.source
    );
    Ok(Study {
        key: "radiosity",
        title: "Radiosity on glossy surfaces".into(),
        row_label: "error".into(),
        col_label: "back-wall strip (alpha)".into(),
        rows: vec!["rel. RMSE".into(), "mean bias (abs.)".into()],
        cols: STRIP_ALPHA
            .iter()
            .map(|a| a.map_or("diffuse".to_string(), |a| a.to_string()))
            .chain(std::iter::once("walls".to_string()))
            .collect(),
        panels,
        ref_noise,
        text,
    })
}

/// The transport study's scenes (name, column label, XML): the Cornell box with a glass ball
/// focusing a small sphere light, or a point light, onto the red wall.
pub const TRANSPORT: [(&str, &str, &str); 2] = [
    (
        "caustic-sphere-light",
        "sphere light (r 0.05)",
        include_str!("../../../../scenes/caustic-sphere-light.xml"),
    ),
    (
        "caustic-point-light",
        "point light",
        include_str!("../../../../scenes/caustic-point-light.xml"),
    ),
];

/// The methods of the transport study, in panel order.
const TRANSPORT_METHODS: [&str; 6] = [
    "path (MIS)",
    "ptracer",
    "sppm",
    "photonmapper",
    "bdpt",
    "vcm",
];

/// The regions of a `w x h` transport image, as fractions of the 128 x 128 film: the caustic
/// (rows 80-92, columns 13-25: the spot the ball focuses on the red wall, around pixel
/// (19, 86) in both scenes' Mitsuba references) and the walls (every other pixel but a disc of
/// radius 16 around the ball's image at (43.8, 68.5): the ball renders black in the light
/// tracer and in the references, which are Mitsuba's `ptracer`, so it is no region).
fn transport_regions(w: u32, h: u32) -> [Vec<usize>; 2] {
    let (sx, sy) = (w as f32 / 128.0, h as f32 / 128.0);
    let caustic = rect(
        w,
        (
            (80.0 * sy) as u32,
            (93.0 * sy).ceil() as u32,
            (13.0 * sx) as u32,
            (26.0 * sx).ceil() as u32,
        ),
    );
    let inside: std::collections::HashSet<usize> = caustic.iter().copied().collect();
    let (cx, cy, r) = (43.8 * sx, 68.5 * sy, 16.0 * sx);
    let walls = (0..(w * h) as usize)
        .filter(|i| {
            let (x, y) = ((i % w as usize) as f32 + 0.5, (i / w as usize) as f32 + 0.5);
            !inside.contains(i) && (x - cx).powi(2) + (y - cy).powi(2) > r * r
        })
        .collect();
    [caustic, walls]
}

/// The Mitsuba `ptracer` reference of transport scene `name` (`NAME.exr` in `o.references` or,
/// as the scene suite's references, in its parent folder); an error without one.
fn transport_reference(
    o: &AtlasSettings,
    name: &str,
    scene: &Scene,
    base: &RenderSettings,
) -> Result<Reference> {
    let folder = if o.references.join(format!("{name}.exr")).is_file() {
        o.references.clone()
    } else {
        o.references
            .parent()
            .map_or_else(|| o.references.clone(), Path::to_path_buf)
    };
    let reference = reference(&folder, name, scene, base, o.fallback_spp)?;
    if !reference.source.starts_with("Mitsuba") {
        return Err(LabError::Invalid(format!(
            "transport: no Mitsuba ptracer reference {name}.exr in {} or its parent (a path-traced stand-in would lack the caustic)",
            o.references.display()
        )));
    }
    Ok(reference)
}

/// A transport scene rendered by each of [`TRANSPORT_METHODS`], in that order: the path
/// tracer (MIS) at `o.spp`, the others at its time (or spp).
fn transport_renders(
    o: &AtlasSettings,
    scene: &Scene,
    base: &RenderSettings,
) -> Result<[RenderOutput; 6]> {
    let settings = RenderSettings {
        seed: SEED,
        ..base.clone()
    };
    pt_integrators::ptracer::check(&settings).map_err(LabError::Invalid)?;
    let photons = pt_integrators::sppm::SppmSettings::default();
    pt_integrators::sppm::check(&photons).map_err(LabError::Invalid)?;
    let path = render_within(
        scene,
        &with_strategy(base, Strategy::Mis),
        Budget::Spp(o.spp),
    );
    let budget = match o.equal {
        Equal::Time => Budget::Time(path.time),
        Equal::Spp => Budget::Spp(o.spp),
    };
    let never = AtomicBool::new(false);
    let light = render_steps(
        &settings,
        budget,
        pt_integrators::RenderState::for_light_paths(&settings),
        |rs, state| {
            pt_integrators::ptracer::render_light_passes(scene, rs, state, &never, None, &|_| {});
        },
    );
    let sppm = render_steps(
        &settings,
        budget,
        pt_integrators::sppm::new_state(&settings),
        |rs, state| {
            pt_integrators::sppm::render_sppm_passes(scene, rs, &photons, state, &never, &|_| {});
        },
    );
    let bidirectional = |params: pt_integrators::vcm::VcmSettings| -> Result<_> {
        pt_integrators::vcm::check(scene, &settings, &params).map_err(LabError::Invalid)?;
        Ok(render_steps(
            &settings,
            budget,
            pt_integrators::RenderState::for_light_paths(&settings),
            |rs, state| {
                pt_integrators::vcm::render_vcm_passes(
                    scene,
                    rs,
                    &params,
                    state,
                    &never,
                    None,
                    &|_| {},
                );
            },
        ))
    };
    let bdpt = bidirectional(pt_integrators::vcm::VcmSettings::bdpt())?;
    let vcm = bidirectional(pt_integrators::vcm::VcmSettings::vcm())?;
    let maps = pt_integrators::photonmap::PhotonMapSettings::default();
    pt_integrators::photonmap::check(&maps).map_err(LabError::Invalid)?;
    let jensen = render_steps(
        &settings,
        budget,
        pt_integrators::sppm::new_state(&settings),
        |rs, state| {
            pt_integrators::photonmap::render_photon_passes(
                scene,
                rs,
                &maps,
                state,
                &never,
                None,
                &|_| {},
            );
        },
    );
    Ok([path, light, sppm, jensen, bdpt, vcm])
}

/// The transport study (on the current rayon pool): each scene rendered by the path tracer
/// (MIS) at `o.spp`, then by the light tracer and SPPM at its time (or spp). References:
/// Mitsuba's `ptracer` images of the scenes (`NAME.exr` in `o.references` or, as the scene
/// suite's references, in its parent folder).
pub fn transport(o: &AtlasSettings) -> Result<Study> {
    check(o)?;
    let mut panels = Panel::empty(TRANSPORT_METHODS.iter().copied(), 2);
    let mut ref_noise = vec![Vec::new(), Vec::new()];
    let mut sources = Vec::new();
    let mut size = (0, 0);
    for (name, _, xml) in TRANSPORT {
        let (scene, base, _) = load(xml, name, o.shrink)?;
        size = (base.width, base.height);
        let reference = transport_reference(o, name, &scene, &base)?;
        sources.push(reference.source.clone());
        let regions = transport_regions(base.width, base.height);
        let outs = transport_renders(o, &scene, &base)?;
        for (k, (panel, out)) in panels.iter_mut().zip(&outs).enumerate() {
            for (g, pixels) in regions.iter().enumerate() {
                let (e, n) = region_error(&out.mean, &reference, pixels);
                panel.cells[g].push(e);
                if k == 0 {
                    ref_noise[g].push(n);
                }
            }
            panel.spp.push(out.spp);
            panel.secs.push(out.time.as_secs_f64());
        }
    }
    let text = format!(
        "Scenes `scenes/caustic-sphere-light.xml` and `scenes/caustic-point-light.xml` (issue 21's caustic): a glass \
         ball (ior 1.5) in the Cornell box focuses a light onto the red wall, {}x{} pixels, max_depth 8; the sphere \
         light (radius 0.05) and the point light (columns) have equal power. Regions: the caustic spot on the red \
         wall, and the walls (every other pixel but the ball's disc: the references are Mitsuba's particle tracer, \
         which cannot show the ball). Budget: {}; the light tracer's spp are light paths per pixel, SPPM's are \
         iterations (one camera path per pixel and as many photons). References: {}. The caustic is light that \
         reaches the wall only through the glass. A path from the camera finds it only when a cosine-sampled \
         direction from the wall passes through the ball onto the light: rarely under the small sphere, never under \
         the point light (a delta light behind a delta surface), where the path tracer's image lacks the focused \
         light at any budget (its caustic error is then the focused light's share of the region). A \
         light path finds it by tracing from the light through the ball and connecting the wall to the camera; \
         SPPM's photons find it the same way and are gathered at the wall's visible points (biased: blurred over \
         the shrinking radius). The photon mapper (Jensen 1996) reads the caustic from its caustic map at the \
         wall's visible points (biased: blurred over its 50 nearest photons). BDPT weighs all of these strategies by the power heuristic (unbiased); VCM adds \
         merging of light vertices at camera vertices under the same weights (biased like SPPM where merging \
         dominates). Both use one camera and one light subpath per pixel per sample.",
        size.0,
        size.1,
        budget_words(o).replace("MIS renders", "path tracing (MIS) renders").replace("the other strategies", "ptracer, sppm, photonmapper, bdpt and vcm"),
        sources.join("; ")
    );
    Ok(Study {
        key: "transport",
        title: "A caustic behind glass: path tracing, light tracing, photon mapping (SPPM, Jensen), BDPT and VCM".into(),
        row_label: "region".into(),
        col_label: "light".into(),
        rows: vec!["caustic".into(), "walls".into()],
        cols: TRANSPORT.iter().map(|t| t.1.to_string()).collect(),
        panels,
        ref_noise,
        text,
    })
}
