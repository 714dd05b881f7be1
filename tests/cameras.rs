//! The cameras against closed forms, end to end through `pt render`.
//!
//! 1. **Orthographic footprint.** An 8 x 8 orthographic film looks straight at an emitting
//!    rectangle whose radiance is a checkerboard with cells exactly one pixel wide in the
//!    scene (the film spans [-1, 1]^2, the rectangle too, to_uv scale 4: cells 1/8 of the
//!    rectangle). The pixel filter is a tent of radius 0.45, so every sample stays inside its
//!    pixel; emitters only (max_depth 1). Then each pixel sees one cell only, and its value is
//!    exactly color0 or color1 (to float rounding, 1e-6 relative) with zero variance, in the
//!    pattern the geometry predicts: pixel (i, j) has u = (i + 1/2) / 8 and v = 1 - (j + 1/2) / 8
//!    (the rectangle is turned to face the camera, +x is the image's left), which puts color0
//!    where i + j is odd (Mitsuba's checkerboard: color0 where the fractional parts of 4u and 4v
//!    are both above 1/2 or both not). Power: the same camera moved by half a pixel sees two
//!    cells in every pixel and must fail the check.
//! 2. **Principal point.** The same checkerboard through a 90-degree perspective camera (the
//!    footprints on the plane are aligned the same way): an offset of 1/8 of the film moves the
//!    pattern by exactly one pixel, half of that straddles cells.
//! 3. **Crop window.** A crop renders the whole film's pixels bit for bit.
//! 4. **A thin lens of aperture 0 is the pinhole.** The same scene through `perspective` and
//!    through `thinlens` with `aperture_radius` 0 gives bit-identical images (the camera draws no
//!    lens sample, so the random numbers match too).
//! 5. **Irradiancemeter.** A disk of radius 0.5 measuring the light of a sphere lamp (radius
//!    0.4, radiance L) hanging above it, nothing else in the scene: at a point whose distance to
//!    the lamp's centre is d and whose normal makes the angle theta with it, the irradiance from
//!    a sphere wholly above the horizon is E = pi L (r / d)^2 cos theta (the projected solid
//!    angle of a sphere); the meter reads its mean over the disk, computed here by midpoint
//!    quadrature (400 x 400 cells in polar coordinates, error far below the test's 0.3%
//!    standard error). At 4M samples the rendered value must lie within 4 of its standard errors
//!    of it (false alarm 6e-5); a 2% error in the weight pi, the cosine sampling or the area
//!    average is over 6 standard errors and fails, which the test also checks of its own
//!    threshold.
//! 6. **Distant sensor.** An emitting square [-1, 1]^2 (radiance 1, facing +z) under a sky of
//!    radiance 0.2, seen by Mitsuba's `distant` sensor: aimed at the scene's bounding disk
//!    (radius sqrt 2 around the square's centre, perpendicular to the direction) from an angle
//!    theta to the square's normal, the value is 0.2 + 0.8 (4 cos theta) / (2 pi), the
//!    fraction of the disk the square covers; aimed at one point of the square exactly 1 (no
//!    variance); aimed at a target rectangle three quarters over the square, 0.8. Each within
//!    4 standard errors (1M samples: 0.06% of the value), a 2% error far outside.

use crate::common;

use common::*;
use pt_image::Image;

const C0: [f32; 3] = [0.8, 0.6, 0.3];
const C1: [f32; 3] = [0.1, 0.25, 0.5];

fn ortho_scene(shift_x: f32) -> String {
    checker_scene(
        &format!(
            r#"<sensor type="orthographic">
        <transform name="to_world"><translate x="{shift_x}"/></transform>"#
        ),
        1.0,
        4.0,
    )
}

/// An 8 x 8 film (16 spp, tent of radius 0.45) behind the sensor opening `sensor`, looking at
/// an emitting checkerboard rectangle of half-size `size` at z = 1 facing it, `to_uv` scaled by
/// `uv_scale`; emitters only.
fn checker_scene(sensor: &str, size: f32, uv_scale: f32) -> String {
    format!(
        r#"<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="1"/></integrator>
    {sensor}
        <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
        <film type="hdrfilm">
            <integer name="width" value="8"/><integer name="height" value="8"/>
            <rfilter type="tent"><float name="radius" value="0.45"/></rfilter>
        </film>
    </sensor>
    <shape type="rectangle">
        <transform name="to_world"><scale value="{size}"/><rotate y="1" angle="180"/><translate z="1"/></transform>
        <emitter type="area">
            <texture type="checkerboard" name="radiance">
                <rgb name="color0" value="{}, {}, {}"/>
                <rgb name="color1" value="{}, {}, {}"/>
                <transform name="to_uv"><scale value="{uv_scale}"/></transform>
            </texture>
        </emitter>
    </shape>
</scene>"#,
        C0[0], C0[1], C0[2], C1[0], C1[1], C1[2]
    )
}

/// Whether every pixel is exactly its predicted cell colour with zero variance; the first
/// pixel that is not, otherwise. `shift`: the image shows the cell pattern moved by this many
/// pixels (pixel (i, j) sees the cell of the centred image's pixel (i + shift, j)).
fn exact_footprints(img: &Image, var: &Image, shift: u32) -> Result<(), String> {
    for j in 0..8 {
        for i in 0..8 {
            let expect = if (i + shift + j) % 2 == 1 { C0 } else { C1 };
            let (got, v) = (img.get(i, j), var.get(i, j));
            for c in 0..3 {
                if (got[c] - expect[c]).abs() > 1e-6 * expect[c] || v[c] != 0.0 {
                    return Err(format!(
                        "pixel ({i}, {j}) channel {c}: {} (variance {}), expected {}",
                        got[c], v[c], expect[c]
                    ));
                }
            }
        }
    }
    Ok(())
}

#[test]
fn orthographic_pixels_see_exactly_their_footprint() {
    let dir = scratch("camera_ortho");
    let mut results = Vec::new();
    for (name, shift) in [("aligned", 0.0f32), ("half_pixel", 0.125)] {
        let path = dir.join(format!("{name}.xml"));
        std::fs::write(&path, ortho_scene(shift)).expect("write scene");
        let (img, var) = render(&path, &dir, name, &[]);
        results.push(exact_footprints(&img, &var, 0));
    }
    assert_eq!(results[0], Ok(()), "aligned film");
    assert!(
        results[1].is_err(),
        "a film moved by half a pixel must straddle cells"
    );
}

/// The checkerboard scene seen through a perspective camera at the origin with a 90-degree
/// field of view: the plane z = 1 spans [-1, 1] across the 8-pixel film, so each pixel's
/// footprint there is 0.25 wide, and the (larger, 4 x 4) emitting rectangle has 16 cells
/// across (to_uv scale 8: two cells per unit of scaled u), 0.25 each, aligned with the pixels (its edge at -2 is 8 pixel widths away). Emitters
/// only, tent radius 0.45: every pixel sees one cell only.
fn perspective_scene(principal_point: [f32; 2]) -> String {
    let [px, py] = principal_point;
    checker_scene(
        &format!(
            r#"<sensor type="perspective">
        <float name="fov" value="90"/>
        <float name="principal_point_offset_x" value="{px}"/>
        <float name="principal_point_offset_y" value="{py}"/>"#
        ),
        2.0,
        8.0,
    )
}

/// Mitsuba's principal point offset moves the image content by -offset x film size pixels
/// (measured with Mitsuba 3.9.1: `principal_point_offset_x` 0.25 on a 200-pixel film moved a
/// point from x 100.0 to 50.0, `_y` -0.15 on 100 pixels from y 50.0 to 65.0). On the aligned
/// checkerboard, an offset of 1/8 on the 8-pixel film moves the pattern by exactly one pixel:
/// each pixel then sees its neighbour's cell, exactly, with zero variance. Power: the centred
/// pattern fails that check, and an offset of half a pixel straddles cells. (The pattern's
/// parity cannot tell left from right: the direction, and the crop window, are checked against
/// Mitsuba by the `crop-principal-point` reference scene.)
#[test]
fn principal_point_offset_moves_the_image_by_whole_pixels() {
    let dir = scratch("camera_principal_point");
    let mut results = Vec::new();
    for (name, pp, shift) in [
        ("centred", [0.0f32, 0.0], 0),
        ("one_pixel", [0.125, 0.0], 1),
        ("centred_as_shifted", [0.0, 0.0], 1),
        ("half_pixel", [0.0625, 0.0], 1),
    ] {
        let path = dir.join(format!("{name}.xml"));
        std::fs::write(&path, perspective_scene(pp)).expect("write scene");
        let (img, var) = render(&path, &dir, name, &[]);
        results.push((name, exact_footprints(&img, &var, shift)));
    }
    assert_eq!(results[0].1, Ok(()), "centred");
    assert_eq!(results[1].1, Ok(()), "moved by one pixel");
    for (name, r) in &results[2..] {
        assert!(r.is_err(), "{name} must not show the moved pattern");
    }
}

/// A crop window with `sample_border` renders the whole film's pixels bit for bit: the same
/// rays (the film position is computed from the pixel's place in the whole film) and the same
/// random streams (keyed by that place). Default gaussian filter (radius 2 pixels), a lens
/// camera, several bounces. Without `sample_border` (Mitsuba's default) the crop's edge pixels
/// draw their filter cut off at the crop's edge, as Mitsuba's do, so they differ, while pixels
/// 2 or more pixels inside stay bit for bit the same. Power: the region one pixel off differs.
#[test]
fn crop_window_renders_the_films_pixels_bit_for_bit() {
    let dir = scratch("camera_crop");
    let scene = |crop: &str| {
        format!(
            r#"<scene version="3.0.0">
    <sensor type="thinlens">
        <float name="fov" value="50"/>
        <float name="aperture_radius" value="0.05"/><float name="focus_distance" value="3"/>
        <transform name="to_world"><lookat origin="0.3, 1.2, 3" target="0, 0.3, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="16"/>{crop}</film>
    </sensor>
    <shape type="sphere"><point name="center" value="0, 0.3, 0"/><float name="radius" value="0.3"/>
        <bsdf type="plastic"/></shape>
    <shape type="rectangle"><transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform></shape>
    <emitter type="constant"><rgb name="radiance" value="1, 0.9, 0.8"/></emitter>
</scene>"#
        )
    };
    let full_path = dir.join("full.xml");
    std::fs::write(&full_path, scene("")).expect("write scene");
    let (full, full_var) = render(&full_path, &dir, "full", &[]);
    let window = r#"<integer name="crop_offset_x" value="7"/><integer name="crop_offset_y" value="5"/>
        <integer name="crop_width" value="11"/><integer name="crop_height" value="6"/>"#;
    let mut crops = Vec::new();
    for (name, border) in [("crop_border", "true"), ("crop", "false")] {
        let path = dir.join(format!("{name}.xml"));
        let film = format!(r#"{window}<boolean name="sample_border" value="{border}"/>"#);
        std::fs::write(&path, scene(&film)).expect("write scene");
        crops.push(render(&path, &dir, name, &[]));
    }
    // The crop's pixels at least `inset` from its edge, and the film's pixels under them moved
    // by `dx`.
    let of_crop = |img: &Image, inset: u32| -> Vec<[f32; 3]> {
        (inset..6 - inset)
            .flat_map(|j| (inset..11 - inset).map(move |i| img.get(i, j)))
            .collect()
    };
    let of_film = |img: &Image, dx: u32, inset: u32| -> Vec<[f32; 3]> {
        (inset..6 - inset)
            .flat_map(|j| (inset..11 - inset).map(move |i| img.get(i + 7 + dx, j + 5)))
            .collect()
    };
    let (crop, crop_var) = &crops[0];
    assert_eq!((crop.width, crop.height), (11, 6));
    assert!(crop.data.iter().any(|p| p[0] > 0.0), "the crop is black");
    assert_eq!(
        of_crop(crop, 0),
        of_film(&full, 0, 0),
        "mean differs from the film's region"
    );
    assert_eq!(
        of_crop(crop_var, 0),
        of_film(&full_var, 0, 0),
        "variance differs"
    );
    assert_ne!(
        of_crop(crop, 0),
        of_film(&full, 1, 0),
        "the region one pixel off must differ"
    );
    let (cut, _) = &crops[1];
    assert_eq!(
        of_crop(cut, 2),
        of_film(&full, 0, 2),
        "pixels 2 inside the crop's edge differ"
    );
    assert_ne!(
        of_crop(cut, 0),
        of_film(&full, 0, 0),
        "the crop's edge must cut the filter"
    );
}

#[test]
fn thin_lens_of_aperture_zero_renders_the_pinhole_image() {
    let dir = scratch("camera_thinlens");
    let scene = |sensor: &str, extra: &str| {
        format!(
            r#"<scene version="3.0.0">
    <sensor type="{sensor}">{extra}
        <float name="fov" value="50"/>
        <transform name="to_world"><lookat origin="0.3, 1.2, 3" target="0, 0.3, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="16"/></film>
    </sensor>
    <shape type="sphere"><point name="center" value="0, 0.3, 0"/><float name="radius" value="0.3"/>
        <bsdf type="plastic"/></shape>
    <shape type="rectangle"><transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform></shape>
    <emitter type="constant"><rgb name="radiance" value="1, 0.9, 0.8"/></emitter>
</scene>"#
        )
    };
    let mut images = Vec::new();
    for (name, xml) in [
        ("pinhole", scene("perspective", "")),
        (
            "lens0",
            scene(
                "thinlens",
                r#"<float name="aperture_radius" value="0"/><float name="focus_distance" value="2"/>"#,
            ),
        ),
    ] {
        let path = dir.join(format!("{name}.xml"));
        std::fs::write(&path, xml).expect("write scene");
        images.push(render(&path, &dir, name, &[]));
    }
    assert!(images[0].0.data.iter().any(|p| p[0] > 0.0));
    assert_eq!(images[0].0.data, images[1].0.data, "mean images differ");
    assert_eq!(images[0].1.data, images[1].1.data, "variance images differ");
}

#[test]
fn irradiancemeter_reads_the_mean_irradiance_of_a_sphere_lamp() {
    let dir = scratch("camera_irradiancemeter");
    let (centre, r, radiance) = ([0.3f64, 0.2, 2.5], 0.4f64, 5.0f64);
    let xml = format!(
        r#"<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="2"/></integrator>
    <shape type="sphere"><point name="center" value="{}, {}, {}"/><float name="radius" value="{r}"/>
        <emitter type="area"><rgb name="radiance" value="{radiance}"/></emitter></shape>
    <shape type="disk"><transform name="to_world"><scale value="0.5"/></transform>
        <sensor type="irradiancemeter">
            <sampler type="independent"><integer name="sample_count" value="4194304"/></sampler>
            <film type="hdrfilm"><integer name="width" value="1"/><integer name="height" value="1"/>
                <rfilter type="box"/></film>
        </sensor>
    </shape>
</scene>"#,
        centre[0], centre[1], centre[2]
    );
    let path = dir.join("meter.xml");
    std::fs::write(&path, xml).expect("write scene");
    let (img, var) = render(&path, &dir, "meter", &[]);
    // The mean of E = pi L (r / d)^2 cos(theta) over the disk, polar midpoint quadrature.
    let n = 400;
    let (mut sum, mut area) = (0.0, 0.0);
    for i in 0..n {
        let rho = 0.5 * (i as f64 + 0.5) / n as f64;
        for j in 0..n {
            let phi = std::f64::consts::TAU * (j as f64 + 0.5) / n as f64;
            let to = [
                centre[0] - rho * phi.cos(),
                centre[1] - rho * phi.sin(),
                centre[2],
            ];
            let d2 = to.iter().map(|c| c * c).sum::<f64>();
            let cos = to[2] / d2.sqrt();
            sum += std::f64::consts::PI * radiance * r * r / d2 * cos * rho;
            area += rho;
        }
    }
    let expected = sum / area;
    let (value, sigma) = (f64::from(img.data[0][0]), f64::from(var.data[0][0]).sqrt());
    let within = |e: f64| (value - e).abs() < 4.0 * sigma;
    assert!(
        sigma < 0.004 * expected,
        "standard error {sigma} too large for the test's power (expected {expected})"
    );
    assert!(
        within(expected),
        "read {value} +- {sigma}, expected {expected}"
    );
    assert!(!within(expected * 1.02) && !within(expected / 1.02));
}

#[test]
fn distant_sensor_averages_over_its_target() {
    let dir = scratch("camera_distant");
    let meter = |sensor_inner: &str, name: &str| {
        let xml = format!(
            r#"<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="1"/></integrator>
    <emitter type="constant"><rgb name="radiance" value="0.2"/></emitter>
    <shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
    <sensor type="distant">{sensor_inner}
        <sampler type="independent"><integer name="sample_count" value="1048576"/></sampler>
        <film type="hdrfilm"><integer name="width" value="1"/><integer name="height" value="1"/></film>
    </sensor>
</scene>"#
        );
        let path = dir.join(format!("{name}.xml"));
        std::fs::write(&path, xml).expect("write scene");
        let (img, var) = render(&path, &dir, name, &[]);
        (f64::from(img.data[0][0]), f64::from(var.data[0][0]).sqrt())
    };
    let theta = 40f64.to_radians();
    let tilted = format!(
        r#"<vector name="direction" value="0, {}, {}"/>"#,
        theta.sin(),
        -theta.cos()
    );
    let disk = |cos: f64| 0.2 + 0.8 * 4.0 * cos / std::f64::consts::TAU;
    for (name, inner, expected) in [
        ("down", r#"<vector name="direction" value="0, 0, -1"/>"#.to_string(), disk(1.0)),
        ("tilted", tilted, disk(theta.cos())),
        (
            "offset_target",
            r#"<vector name="direction" value="0, 0, -1"/>
        <shape type="rectangle" name="target"><transform name="to_world"><scale x="0.5" y="0.25"/><translate x="0.75"/></transform></shape>"#
                .to_string(),
            0.75 + 0.25 * 0.2,
        ),
    ] {
        let (value, sigma) = meter(&inner, name);
        assert!(sigma < 0.001 * expected, "{name}: standard error {sigma}");
        let within = |e: f64| (value - e).abs() < 4.0 * sigma;
        assert!(within(expected), "{name}: read {value} +- {sigma}, expected {expected}");
        assert!(!within(expected * 1.02) && !within(expected / 1.02), "{name}");
    }
    let (value, sigma) = meter(
        r#"<vector name="direction" value="0.3, -0.2, -1"/><point name="target" value="0.3, 0.2, 0"/>"#,
        "point",
    );
    assert_eq!((value, sigma), (1.0, 0.0), "a point on the square");
}
