//! Media and transparency against closed forms: Beer-Lambert absorption inside glass, opacity
//! masks, and scattering media in a furnace.
//!
//! 1. A glass slab (ior 1.5 in vacuum, thickness d, filled with a purely absorbing medium of
//!    extinction sigma) under a constant environment of radiance 1, seen along its normal through
//!    a 2-degree field of view. Along the normal every path stays on one line, so the radiance is
//!    the slab's total reflectance plus total transmittance (the geometric series of internal
//!    reflections, e.g. Born & Wolf ch. 1.6 / any optics text), with R = ((n-1)/(n+1))^2 and the
//!    single-pass transmittance tau = exp(-sigma d):
//!    R_tot = R + (1-R)^2 R tau^2 / (1 - R^2 tau^2),   T_tot = (1-R)^2 tau / (1 - R^2 tau^2).
//!    Off-axis rays (at most 1 degree outside, 0.67 degrees inside the glass) lengthen the path by
//!    under 7e-5 relative: far below the tolerance.
//! 2. `path` ignores the medium (as Mitsuba's does): the same slab gives exactly R_tot + T_tot at
//!    tau = 1, which is 1.
//! 3. A mask of opacity a over a two-sided diffuse plane of albedo rho, under the same
//!    environment: L = a rho + (1 - a) (the null lobe lets the environment behind through).
//!
//! 4. The scattering furnace: a black sphere whose inner surface emits radiance 1, filled with a
//!    medium of albedo 1 (chromatic extinction, forward Henyey-Greenstein phase), seen by a
//!    camera inside the medium. The medium scatters without loss and the walls emit what they
//!    absorb from it, so radiance is 1 everywhere in every direction (the RTE's solution for a
//!    conservative medium under a uniform boundary), whatever the extinction and phase: a
//!    wrong free-flight weight, phase normalisation, light-sampling transmittance or MIS weight
//!    moves it. The same in spectral mode (a tabulated extinction), against the sphere seen
//!    without the medium.
//! 5. The same sphere filled with a purely absorbing medium, the camera at its centre: every
//!    ray crosses the radius R, L = exp(-sigma_t R).
//!
//! 6. Single scattering of a collimated beam in a slab: a directional light (irradiance E = 1)
//!    shines along +z into a slab of thickness d (a null-walled box, chromatic extinction
//!    sigma_t, albedo a, Henyey-Greenstein g = 0.5), seen from above through a 2-degree field of
//!    view with `max_depth` 2 (one scattering event, in volpath's and ptracer's counting). Along
//!    a camera ray at angle alpha from the axis (c = cos alpha), light scattered at height u
//!    above the bottom has crossed u of the beam and (d - u) / c towards the camera:
//!    L = a sigma_t E p(alpha) e^(-sigma_t d / c) (e^(k d) - 1) / (k c), k = sigma_t (1/c - 1)
//!    (d / c e^(-sigma_t d) as k -> 0), averaged over the pixels' central directions. The
//!    forward-scattering phase value is 0.477/sr against 0.018/sr backwards: a phase function
//!    evaluated the wrong way round, or a missing transmittance on either leg, fails by far.
//!
//! 7. Volume emission (pt's `emission`, the source term j of the transfer equation): a camera
//!    at the centre of a black sphere of radius 30 filled with a glowing, scattering medium
//!    (chromatic extinction 1-4 per unit, albedo 0.6, Henyey-Greenstein g = 0.5). At 30 mean
//!    free paths or more from the walls the medium is infinite to e^-30, and the transfer
//!    equation's solution there is uniform and isotropic, L sigma_t = j + sigma_s L, so
//!    L = j / sigma_a. The same as a heterogeneous medium of constant RGB grids (extinction,
//!    albedo and emission each a gridvolume: delta tracking's collision estimator of emission,
//!    RGB grids, an albedo grid), and in spectral mode (against an emitting sphere in vacuum:
//!    the same spectrum). Emission counted once per segment instead of per scattering event,
//!    or divided by sigma_t instead of gathered along the path, misses by the albedo's factor.
//!
//! Threshold: the image mean (16x16 pixels, 1024 spp: 262144 paths; the furnaces 16384 spp) must lie within 4.5 of its
//! standard errors (from the variance image) plus 2e-4 (float32 accumulation) of the closed form,
//! and the standard error must be below 0.25% of the value, so that a 2% bias (say, sigma used
//! as exp(-sigma d / 2), a missing internal reflection, a mask weight of a instead of 1) fails.

use crate::common;

use common::*;

const SPP: &str = "1024";

fn slab_scene(integrator: &str, sigma: [f64; 3], d: f64) -> String {
    let sensor = sensor_xml(2.0, [0.0, 0.0, 10.0], 16, 16, 16);
    format!(
        r#"<scene version="3.0.0">
    <integrator type="{integrator}"/>
    {sensor}
    <emitter type="constant"><float name="radiance" value="1"/></emitter>
    <shape type="cube">
        <transform name="to_world"><scale value="5, 5, {half}"/></transform>
        <bsdf type="dielectric"><float name="int_ior" value="1.5"/><float name="ext_ior" value="1"/></bsdf>
        <medium type="homogeneous" name="interior">
            <rgb name="sigma_t" value="{s0}, {s1}, {s2}"/>
            <float name="albedo" value="0"/>
        </medium>
    </shape>
</scene>"#,
        half = d / 2.0,
        s0 = sigma[0],
        s1 = sigma[1],
        s2 = sigma[2]
    )
}

/// Checks the image mean against `want` (see the module doc for the threshold).
fn check_mean(name: &str, xml: &str, want: [f64; 3]) {
    check_mean_at(name, xml, want, SPP);
}

/// [`check_mean`] at `spp` samples per pixel.
fn check_mean_at(name: &str, xml: &str, want: [f64; 3], spp: &str) {
    let dir = scratch(&format!("media_{name}"));
    let path = dir.join("scene.xml");
    std::fs::write(&path, xml).unwrap();
    let (img, var) = render(&path, &dir, "out", &["--spp", spp]);
    let (m, se) = mean_and_stderr(&img, &var);
    for c in 0..3 {
        let z = (m[c] - want[c]).abs() / se[c].max(1e-12);
        eprintln!(
            "{name} channel {c}: got {:.5} want {:.5} (stderr {:.2e}, z {z:.2})",
            m[c], want[c], se[c]
        );
        assert!(
            se[c] < 0.0025 * want[c],
            "{name}: standard error {} too large to detect a 2% bias",
            se[c]
        );
        assert!(
            (m[c] - want[c]).abs() <= 4.5 * se[c] + 2e-4,
            "{name} channel {c}: {} vs closed form {} (z = {z:.1})",
            m[c],
            want[c]
        );
    }
}

/// R_tot + T_tot of an absorbing slab at normal incidence (module doc).
fn slab_radiance(n: f64, tau: f64) -> f64 {
    let r = ((n - 1.0) / (n + 1.0)).powi(2);
    let denom = 1.0 - r * r * tau * tau;
    r + (1.0 - r).powi(2) * r * tau * tau / denom + (1.0 - r).powi(2) * tau / denom
}

#[test]
fn absorbing_slab_matches_beer_lambert_series() {
    let (sigma, d) = ([0.2, 0.5, 1.0], 2.0f64);
    let want = sigma.map(|s| slab_radiance(1.5, (-s * d).exp()));
    check_mean("slab_volpath", &slab_scene("volpath", sigma, d), want);
}

#[test]
fn path_integrator_ignores_media_like_mitsuba() {
    let want = [slab_radiance(1.5, 1.0); 3];
    assert!((want[0] - 1.0).abs() < 1e-12);
    check_mean("slab_path", &slab_scene("path", [0.2, 0.5, 1.0], 2.0), want);
}

#[test]
fn mask_lets_the_background_through_its_holes() {
    let (a, rho) = (0.3, [0.8, 0.5, 0.1]);
    let sensor = sensor_xml(20.0, [0.0, 0.0, 10.0], 16, 16, 16);
    let xml = format!(
        r#"<scene version="3.0.0">
    <integrator type="path"/>
    {sensor}
    <emitter type="constant"><float name="radiance" value="1"/></emitter>
    <shape type="rectangle">
        <transform name="to_world"><scale value="5, 5, 1"/></transform>
        <bsdf type="mask"><float name="opacity" value="{a}"/>
            <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="{}, {}, {}"/></bsdf></bsdf>
        </bsdf>
    </shape>
</scene>"#,
        rho[0], rho[1], rho[2]
    );
    check_mean("mask", &xml, rho.map(|r| a * r + (1.0 - a)));
}

/// Samples per pixel of the furnaces: paths scatter many times in them (optical radius up to
/// 2.5), and 16384 per pixel bring the standard error below 0.25% in every channel.
const FURNACE_SPP: &str = "16384";

/// The furnace of the module doc (items 4 and 5): a black sphere of radius 1 emitting radiance 1
/// inwards, filled with `medium` (the XML of a `<medium ... id="m">`), the camera at its centre
/// inside the same medium (or in vacuum when `medium` is empty).
fn furnace_scene(medium: &str) -> String {
    let (declare, sensor_ref, interior_ref) = if medium.is_empty() {
        (String::new(), "", "")
    } else {
        (
            medium.to_string(),
            r#"<ref id="m"/>"#,
            r#"<ref name="interior" id="m"/>"#,
        )
    };
    format!(
        r#"<scene version="3.0.0">
    <integrator type="volpath"/>
    {declare}
    <sensor type="perspective">
        <float name="fov" value="70"/>
        <transform name="to_world"><lookat origin="0.1, 0.2, 0" target="1, 0.3, -2" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/><rfilter type="box"/></film>
        {sensor_ref}
    </sensor>
    <shape type="sphere">
        <boolean name="flip_normals" value="true"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf>
        <emitter type="area"><rgb name="radiance" value="1, 1, 1"/></emitter>
        {interior_ref}
    </shape>
</scene>"#
    )
}

#[test]
fn conservative_medium_in_a_furnace_keeps_radiance_one() {
    let medium = r#"<medium type="homogeneous" id="m">
        <rgb name="sigma_t" value="0.5, 1, 2"/>
        <float name="albedo" value="1"/>
        <phase type="hg"><float name="g" value="0.6"/></phase>
    </medium>"#;
    check_mean_at("furnace_rgb", &furnace_scene(medium), [1.0; 3], FURNACE_SPP);
}

#[test]
fn conservative_medium_in_a_furnace_keeps_radiance_one_spectrally() {
    // The emitter's colour in spectral mode: the sphere without the medium, rendered with as
    // many samples, both means' standard errors in the threshold.
    let spectral = r#"<spectrum name="radiance" value="400:1, 700:1"/>"#;
    let vacuum = furnace_scene("").replace(r#"<rgb name="radiance" value="1, 1, 1"/>"#, spectral);
    let medium = r#"<medium type="homogeneous" id="m">
        <spectrum name="sigma_t" value="380:0.4, 550:1.2, 780:2.5"/>
        <float name="albedo" value="1"/>
        <phase type="isotropic"/>
    </medium>"#;
    let full = furnace_scene(medium).replace(r#"<rgb name="radiance" value="1, 1, 1"/>"#, spectral);
    let mut means = Vec::new();
    for (name, xml) in [("vacuum", vacuum), ("medium", full)] {
        let dir = scratch(&format!("media_furnace_spectral_{name}"));
        let path = dir.join("scene.xml");
        std::fs::write(&path, &xml).unwrap();
        let (img, var) = render(&path, &dir, "out", &["--spp", FURNACE_SPP]);
        means.push(mean_and_stderr(&img, &var));
    }
    let ((want, se_want), (got, se_got)) = (means[0], means[1]);
    for c in 0..3 {
        let se = se_want[c].hypot(se_got[c]);
        eprintln!(
            "furnace_spectral channel {c}: medium {:.5} vacuum {:.5} (stderr {se:.2e})",
            got[c], want[c]
        );
        assert!(se < 0.0025 * want[c], "standard error {se} too large");
        assert!(
            (got[c] - want[c]).abs() <= 4.5 * se,
            "channel {c}: {} with the medium, {} without",
            got[c],
            want[c]
        );
    }
}

#[test]
fn absorbing_medium_around_the_camera_attenuates_by_the_radius() {
    let sigma: [f64; 3] = [0.3, 0.7, 1.5];
    let medium = format!(
        r#"<medium type="homogeneous" id="m">
        <rgb name="sigma_t" value="{}, {}, {}"/>
        <float name="albedo" value="0"/>
    </medium>"#,
        sigma[0], sigma[1], sigma[2]
    );
    // The camera moved to the centre: every ray crosses the unit radius.
    let xml = furnace_scene(&medium).replace(
        r#"<lookat origin="0.1, 0.2, 0""#,
        r#"<lookat origin="0, 0, 0""#,
    );
    check_mean("absorbing_centre", &xml, sigma.map(|s| (-s).exp()));
}

/// The glowing medium of the module doc (item 7): `medium` (the XML of a `<medium ...
/// id="m">`) fills a black sphere of radius 30 and holds the camera at its centre.
fn glowing_scene(medium: &str) -> String {
    furnace_scene(medium)
        .replace(
            r#"<lookat origin="0.1, 0.2, 0""#,
            r#"<lookat origin="0, 0, 0""#,
        )
        .replace(
            r#"<emitter type="area"><rgb name="radiance" value="1, 1, 1"/></emitter>"#,
            r#"<float name="radius" value="30"/>"#,
        )
}

/// Extinction, albedo and emission of the glowing medium (module doc, 7).
const GLOW_SIGMA: [f64; 3] = [1.0, 2.0, 4.0];
const GLOW_ALBEDO: f64 = 0.6;
const GLOW_J: [f64; 3] = [0.3, 0.5, 0.8];

/// The grid medium's extinction: less chromatic than [`GLOW_SIGMA`], since delta tracking
/// against the largest channel's majorant gives the others noisy null-collision weights.
const GLOW_GRID_SIGMA: [f64; 3] = [2.0, 2.5, 3.0];

/// L = j / sigma_a of a glowing medium of extinction `sigma`.
fn glow_radiance(sigma: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|c| GLOW_J[c] / ((1.0 - GLOW_ALBEDO) * sigma[c]))
}

#[test]
fn infinite_glowing_medium_has_radiance_j_over_sigma_a() {
    let [s0, s1, s2] = GLOW_SIGMA;
    let [j0, j1, j2] = GLOW_J;
    let medium = format!(
        r#"<medium type="homogeneous" id="m">
        <rgb name="sigma_t" value="{s0}, {s1}, {s2}"/>
        <float name="albedo" value="{GLOW_ALBEDO}"/>
        <rgb name="emission" value="{j0}, {j1}, {j2}"/>
        <phase type="hg"><float name="g" value="0.5"/></phase>
    </medium>"#
    );
    check_mean(
        "glow_homogeneous",
        &glowing_scene(&medium),
        glow_radiance(GLOW_SIGMA),
    );
}

#[test]
fn infinite_glowing_grid_medium_has_radiance_j_over_sigma_a() {
    use pt_scene::volgrid::{write_vol, VolumeGrid};
    let dir = scratch("media_glow_grid_files");
    let constant = |values: &[f64]| VolumeGrid {
        resolution: [2, 2, 2],
        channels: values.len() as u32,
        bbox: [[0.0; 3], [1.0; 3]],
        values: (0..8)
            .flat_map(|_| values.iter().map(|&v| v as f32))
            .collect(),
    };
    for (name, g) in [
        ("sigma.vol", constant(&GLOW_GRID_SIGMA)),
        ("albedo.vol", constant(&[GLOW_ALBEDO])),
        ("emission.vol", constant(&GLOW_J)),
    ] {
        std::fs::write(dir.join(name), write_vol(&g)).unwrap();
    }
    // The grids fill a cube of side 60 around the camera (the medium ends at the extinction
    // grid's box; the walls are the cube's, black).
    let to_world = r#"<transform name="to_world"><translate value="-0.5, -0.5, -0.5"/><scale value="60"/></transform>"#;
    let grid = |name: &str, file: &str| {
        format!(
            r#"<volume type="gridvolume" name="{name}"><string name="filename" value="{}"/>{to_world}</volume>"#,
            dir.join(file).display()
        )
    };
    let medium = format!(
        r#"<medium type="heterogeneous" id="m">
        {}{}{}
        <phase type="hg"><float name="g" value="0.5"/></phase>
    </medium>"#,
        grid("sigma_t", "sigma.vol"),
        grid("albedo", "albedo.vol"),
        grid("emission", "emission.vol")
    );
    let xml = glowing_scene(&medium).replace(
        r#"<shape type="sphere">"#,
        r#"<shape type="cube"><transform name="to_world"><scale value="30"/></transform>"#,
    );
    let xml = xml.replace(r#"<float name="radius" value="30"/>"#, "");
    check_mean_at(
        "glow_grids",
        &xml,
        glow_radiance(GLOW_GRID_SIGMA),
        FURNACE_SPP,
    );
}

#[test]
fn infinite_glowing_medium_spectrally() {
    // Equal-energy emission j = 0.4 in a grey medium with sigma_a = 1: L = 0.4 E, the radiance
    // of a sphere emitting 0.4 E seen in vacuum (rendered with as many samples; both means'
    // standard errors in the threshold).
    let spectral = r#"<spectrum name="radiance" value="400:0.4, 700:0.4"/>"#;
    let vacuum = furnace_scene("").replace(r#"<rgb name="radiance" value="1, 1, 1"/>"#, spectral);
    let medium = r#"<medium type="homogeneous" id="m">
        <float name="sigma_t" value="2"/>
        <float name="albedo" value="0.5"/>
        <spectrum name="emission" value="400:0.4, 700:0.4"/>
    </medium>"#;
    let glowing = glowing_scene(medium);
    let mut means = Vec::new();
    for (name, xml) in [("vacuum", vacuum), ("medium", glowing)] {
        let dir = scratch(&format!("media_glow_spectral_{name}"));
        let path = dir.join("scene.xml");
        std::fs::write(&path, &xml).unwrap();
        let (img, var) = render(&path, &dir, "out", &["--spp", SPP]);
        means.push(mean_and_stderr(&img, &var));
    }
    let ((want, se_want), (got, se_got)) = (means[0], means[1]);
    for c in 0..3 {
        let se = se_want[c].hypot(se_got[c]);
        eprintln!(
            "glow_spectral channel {c}: medium {:.5} vacuum {:.5} (stderr {se:.2e})",
            got[c], want[c]
        );
        assert!(se < 0.0025 * want[c], "standard error {se} too large");
        assert!(
            (got[c] - want[c]).abs() <= 4.5 * se + 2e-4,
            "channel {c}: {} in the glowing medium, {} from the sphere",
            got[c],
            want[c]
        );
    }
}

/// The light tracer does not start paths in glowing media: a located refusal, no output.
#[test]
fn light_tracer_refuses_glowing_media() {
    let dir = scratch("media_glow_refused");
    let path = dir.join("scene.xml");
    let medium = r#"<medium type="homogeneous" id="m"><float name="emission" value="1"/></medium>"#;
    std::fs::write(&path, glowing_scene(medium)).unwrap();
    let out = dir.join("out.exr");
    let o = pt(&[
        "render",
        path.to_str().unwrap(),
        "--integrator",
        "ptracer",
        "--spp",
        "1",
        "-o",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("glowing media"), "{err}");
    assert!(!out.exists(), "ptracer wrote an image");
}

/// The light-side methods that do not trace media (all but `ptracer`, which does: its images
/// are judged in tests/ptracer.rs) refuse them with a clear error (exit code 2, no output)
/// rather than render them as vacuum.
#[test]
fn light_side_methods_refuse_media() {
    let dir = scratch("media_refused");
    for method in ["bdpt", "vcm", "sppm", "photonmapper"] {
        let out = dir.join(format!("{method}.exr"));
        let o = pt(&[
            "render",
            "scenes/fog-spot.xml",
            "--integrator",
            method,
            "--spp",
            "1",
            "-o",
            out.to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{method}: {err}");
        assert!(
            err.contains("does not yet trace participating media"),
            "{method}: {err}"
        );
        assert!(!out.exists(), "{method} wrote an image");
    }
}

/// A slab of scattering medium under a collimated beam, seen from above (module doc, 6).
fn beam_slab_scene(integrator: &str, sigma: [f64; 3], albedo: f64, g: f64, d: f64) -> String {
    let sensor = sensor_xml(2.0, [0.0, 0.0, 10.0], 16, 16, 16);
    format!(
        r#"<scene version="3.0.0">
    <integrator type="{integrator}"><integer name="max_depth" value="2"/></integrator>
    {sensor}
    <emitter type="directional">
        <vector name="direction" value="0, 0, 1"/>
        <float name="irradiance" value="1"/>
    </emitter>
    <shape type="cube">
        <transform name="to_world"><scale value="0.5, 0.5, {half}"/></transform>
        <bsdf type="null"/>
        <medium type="homogeneous" name="interior">
            <rgb name="sigma_t" value="{s0}, {s1}, {s2}"/>
            <float name="albedo" value="{albedo}"/>
            <phase type="hg"><float name="g" value="{g}"/></phase>
        </medium>
    </shape>
</scene>"#,
        half = d / 2.0,
        s0 = sigma[0],
        s1 = sigma[1],
        s2 = sigma[2]
    )
}

/// The single-scattered radiance of [`beam_slab_scene`] averaged over its 16 x 16 pixels'
/// central directions (module doc, 6).
fn beam_slab_radiance(sigma_t: f64, albedo: f64, g: f64, d: f64) -> f64 {
    let tan_half = 1f64.to_radians().tan();
    let mut sum = 0.0;
    for j in 0..16 {
        for i in 0..16 {
            let x = ((i as f64 + 0.5) / 16.0 - 0.5) * 2.0 * tan_half;
            let y = ((j as f64 + 0.5) / 16.0 - 0.5) * 2.0 * tan_half;
            let c = 1.0 / (1.0 + x * x + y * y).sqrt();
            let phase = (1.0 - g * g)
                / (4.0 * std::f64::consts::PI * (1.0 + g * g - 2.0 * g * c).powf(1.5));
            let k = sigma_t * (1.0 / c - 1.0);
            let path = if k * d < 1e-12 {
                d / c
            } else {
                (k * d).exp_m1() / (k * c)
            };
            sum += albedo * sigma_t * phase * (-sigma_t * d / c).exp() * path;
        }
    }
    sum / 256.0
}

#[test]
fn single_scattering_of_a_collimated_beam_in_a_slab() {
    let (sigma, albedo, g, d) = ([0.4, 0.7, 1.0], 0.8, 0.5, 1.0);
    let want = sigma.map(|s| beam_slab_radiance(s, albedo, g, d));
    // The light tracer's paths scatter all over the slab and few land in the small view: it
    // needs 32 times the samples for the same standard error.
    for (integrator, spp) in [("volpath", SPP), ("ptracer", "32768")] {
        check_mean_at(
            &format!("beam_slab_{integrator}"),
            &beam_slab_scene(integrator, sigma, albedo, g, d),
            want,
            spp,
        );
    }
}
