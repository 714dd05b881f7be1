//! Lights against closed forms: a Lambertian plane (albedo rho, facing +y) seen from straight
//! above, lit by one light. The outgoing radiance is L = rho / pi * E(p) with E the irradiance:
//! - point light of intensity I at height h: E = I h / d^3 (inverse square times cosine; at
//!   horizontal distance x, E = I h / (h^2 + x^2)^(3/2));
//! - spot light: the same times Mitsuba's falloff (1 inside beam_width, linear in angle to 0 at
//!   the cutoff);
//! - directional light of irradiance E0 arriving at angle theta: E = E0 cos(theta);
//! - sun (cone of half-angle alpha, radiance E0 / (pi sin^2 alpha)): E = E0 cos(theta) exactly,
//!   since the cosine-weighted solid angle of a cone above the horizon is pi sin^2(alpha) times the
//!   cosine of its axis;
//! - constant environment L_env: the plane sees the whole upper hemisphere, E = pi L_env, so
//!   L = rho L_env, and camera rays that miss the plane see L_env.
//!
//! Each pixel's expected value is the box-filter average of L over the pixel's footprint,
//! integrated numerically (16 x 16 midpoint rule; its error is below 1e-4 relative here). The
//! render must agree per pixel within 4.5 standard errors plus 2e-4 relative (quadrature and
//! float32 rounding), and its mean within 0.2%: an inverse-distance instead of inverse-square
//! falloff, a missing cosine, a wrong solid-angle pdf or a 2% bias all fail. The standard error is
//! the larger of the render's own estimate and the one implied by the pixel footprint (the
//! variance of L over the pixel divided by spp, from the same quadrature): a pixel that a spot's
//! cutoff cuts in a thin sliver may get no sample inside it, and then its own variance is 0.

use crate::common;

use common::*;

const W: u32 = 24;
const H: f64 = 4.0; // camera height above the plane
const TAN: f64 = 0.4663076581549986; // tan(25 deg): fov 50 on x, square image
const RHO: f64 = 0.6;
const SPP: f64 = 64.0;

fn scene(light: &str, max_depth: i32) -> String {
    format!(
        r#"<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="{max_depth}"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="50"/>
        <transform name="to_world"><lookat origin="0, {H}, 0" target="0, 0, 0" up="0, 0, -1"/></transform>
        <sampler type="independent"><integer name="sample_count" value="64"/></sampler>
        <film type="hdrfilm"><integer name="width" value="{W}"/><integer name="height" value="{W}"/><rfilter type="box"/></film>
    </sensor>
    <shape type="rectangle">
        <transform name="to_world"><scale value="3, 3, 1"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="diffuse"><float name="reflectance" value="{RHO}"/></bsdf>
    </shape>
    {light}
</scene>"#
    )
}

/// World point on the plane y = 0 seen at film position (u, v) in [0,1]^2 (see the camera
/// above: image right is +x, image top is -z).
fn plane_point(u: f64, v: f64) -> (f64, f64) {
    (H * (2.0 * u - 1.0) * TAN, H * (2.0 * v - 1.0) * TAN)
}

/// Renders `light` over the plane and compares every pixel with the footprint average of
/// `radiance(x, z)` (None where the camera ray misses the plane: then `background`).
fn check(name: &str, light: &str, radiance: impl Fn(f64, f64) -> [f64; 3], background: [f64; 3]) {
    let dir = scratch(&format!("lights_{name}"));
    let path = dir.join("scene.xml");
    std::fs::write(&path, scene(light, 2)).unwrap();
    let (img, var) = render(&path, &dir, "out", &[]);
    let n = 16;
    let mut sum_got = 0.0;
    let mut sum_want = 0.0;
    for py in 0..W {
        for px in 0..W {
            let mut want = [0.0f64; 3];
            let mut want_sq = [0.0f64; 3];
            for j in 0..n {
                for i in 0..n {
                    let u = (px as f64 + (i as f64 + 0.5) / n as f64) / W as f64;
                    let v = (py as f64 + (j as f64 + 0.5) / n as f64) / W as f64;
                    let (x, z) = plane_point(u, v);
                    let l = if x.abs() <= 3.0 && z.abs() <= 3.0 {
                        radiance(x, z)
                    } else {
                        background
                    };
                    for c in 0..3 {
                        want[c] += l[c] / (n * n) as f64;
                        want_sq[c] += l[c] * l[c] / (n * n) as f64;
                    }
                }
            }
            let got = img.get(px, py);
            let sd = var.get(px, py);
            for c in 0..3 {
                let footprint_var = (want_sq[c] - want[c] * want[c]).max(0.0) / SPP;
                let tol =
                    4.5 * (sd[c] as f64).max(footprint_var).sqrt() + 2e-4 * want[c].abs() + 1e-7;
                assert!(
                    (got[c] as f64 - want[c]).abs() <= tol,
                    "{name}: pixel ({px}, {py}) channel {c}: got {} want {} (tol {tol:.3e})",
                    got[c],
                    want[c]
                );
                sum_got += got[c] as f64;
                sum_want += want[c];
            }
        }
    }
    assert!(
        (sum_got / sum_want - 1.0).abs() < 2e-3,
        "{name}: mean ratio {}",
        sum_got / sum_want
    );
}

#[test]
fn point_light_inverse_square_and_cosine() {
    let (lx, lh, lz, i) = (0.7, 1.5, -0.4, 5.0);
    check(
        "point",
        &format!(
            r#"<emitter type="point"><point name="position" value="{lx}, {lh}, {lz}"/><rgb name="intensity" value="{i}, {}, {}"/></emitter>"#,
            i * 0.5,
            i * 0.25
        ),
        |x, z| {
            let d2 = (x - lx).powi(2) + lh * lh + (z - lz).powi(2);
            let e = i * lh / d2.powf(1.5); // I h / (h^2 + x^2)^(3/2)
            [
                RHO / std::f64::consts::PI * e,
                RHO / std::f64::consts::PI * e * 0.5,
                RHO / std::f64::consts::PI * e * 0.25,
            ]
        },
        [0.0; 3],
    );
}

#[test]
fn spot_light_falloff() {
    // Spot at height 2 pointing straight down; cutoff 30, beam width 15 degrees.
    let (h, i, cutoff, beam) = (2.0f64, 8.0f64, 30.0f64, 15.0f64);
    check(
        "spot",
        &format!(
            r#"<emitter type="spot"><rgb name="intensity" value="{i}"/><float name="cutoff_angle" value="{cutoff}"/><float name="beam_width" value="{beam}"/>
                <transform name="to_world"><lookat origin="0, {h}, 0" target="0, 0, 0" up="0, 0, 1"/></transform></emitter>"#
        ),
        |x, z| {
            let d2 = x * x + h * h + z * z;
            let angle = (h / d2.sqrt()).acos().to_degrees();
            let fall = if angle <= beam {
                1.0
            } else if angle >= cutoff {
                0.0
            } else {
                (cutoff - angle) / (cutoff - beam)
            };
            let e = i * fall * h / d2.powf(1.5);
            [RHO / std::f64::consts::PI * e; 3]
        },
        [0.0; 3],
    );
}

#[test]
fn directional_and_sun_give_e_cos_theta() {
    // Light travelling along (0.6, -0.8, 0): cos(theta) = 0.8 on the plane.
    let e0 = 3.0;
    let want = RHO / std::f64::consts::PI * e0 * 0.8;
    check(
        "directional",
        &format!(
            r#"<emitter type="directional"><vector name="direction" value="0.6, -0.8, 0"/><rgb name="irradiance" value="{e0}"/></emitter>"#
        ),
        |_, _| [want; 3],
        [0.0; 3],
    );
    // The sun is outside the camera's view, so the background stays black; a 5-degree disk
    // makes a cone wide enough that a wrong cone pdf would show.
    check(
        "sun",
        &format!(
            r#"<emitter type="sun"><vector name="direction" value="0.6, -0.8, 0"/><rgb name="irradiance" value="{e0}"/><float name="angular_diameter" value="5"/></emitter>"#
        ),
        |_, _| [want; 3],
        [0.0; 3],
    );
}

#[test]
fn constant_environment_reflects_rho_times_l() {
    let l = 0.8;
    check(
        "constant",
        &format!(r#"<emitter type="constant"><rgb name="radiance" value="{l}"/></emitter>"#),
        |_, _| [RHO * l; 3],
        [l; 3],
    );
}

/// An environment map with a bright spot and a gradient, lighting the plane. There is no simple
/// closed form, so the test uses the fact that light sampling alone and BSDF sampling alone are
/// independent unbiased estimators of the same image: a wrong envmap pdf (or a sampling routine
/// that disagrees with it) makes them differ. Compared with the block z-test (8x8 blocks,
/// Sidak-corrected alpha 0.01) and the image means within 4.5 standard errors.
#[test]
fn envmap_light_sampling_agrees_with_bsdf_sampling() {
    let dir = scratch("lights_envmap");
    let (ew, eh) = (64u32, 32u32);
    let mut env = pt_image::Image::new(ew, eh);
    for y in 0..eh {
        for x in 0..ew {
            let (u, v) = ((x as f32 + 0.5) / ew as f32, (y as f32 + 0.5) / eh as f32);
            let spot = (-((u - 0.3).powi(2) + (v - 0.3).powi(2)) / 0.002).exp() * 40.0;
            env.set(
                x,
                y,
                [
                    0.2 + spot + 0.5 * (1.0 - v),
                    0.3 + 0.5 * spot,
                    0.4 * u + 0.1,
                ],
            );
        }
    }
    pt_image::write_exr(&dir.join("sky.exr"), &env, &Default::default()).unwrap();
    let path = dir.join("scene.xml");
    let light = r#"<emitter type="envmap"><string name="filename" value="sky.exr"/><transform name="to_world"><rotate y="1" angle="30"/></transform></emitter>"#;
    std::fs::write(&path, scene(light, 2)).unwrap();
    let (a, va) = render(
        &path,
        &dir,
        "light",
        &["--strategy", "light", "--spp", "256"],
    );
    let (b, vb) = render(&path, &dir, "bsdf", &["--strategy", "bsdf", "--spp", "256"]);
    let (c, vc) = render(&path, &dir, "mis", &["--spp", "256"]);
    for (x, vx, y, vy, what) in [
        (&a, &va, &b, &vb, "light vs bsdf"),
        (&c, &vc, &b, &vb, "mis vs bsdf"),
    ] {
        let z = pt_stats::block_ztest(x, vx, y, vy, 8, 0.01).unwrap();
        assert!(
            z.pass,
            "{what}: max |z| {:.2}, {} of {} blocks fail, chi2 p {:.3}",
            z.max_abs_z, z.failed, z.tests, z.chi2_p
        );
        let (mx, sx) = mean_and_stderr(x, vx);
        let (my, sy) = mean_and_stderr(y, vy);
        for ch in 0..3 {
            let zz = (mx[ch] - my[ch]) / sx[ch].hypot(sy[ch]);
            assert!(
                zz.abs() < 4.5,
                "{what} channel {ch}: means {} vs {} (z {zz:.2})",
                mx[ch],
                my[ch]
            );
        }
    }
}

/// A spherical area light (radiance L, radius r, centre at height h, outside the view) over the
/// plane: a uniform sphere fully above the horizon gives E = pi L (r/d)^2 cos(theta), so
/// L_out = rho L r^2 h / d^3. Checks solid-angle (cone) sampling of spheres and its pdf in MIS,
/// for each strategy.
#[test]
fn sphere_light_solid_angle_sampling() {
    let (cx, h, r, l) = (2.5, 1.0, 0.3, 20.0);
    let light = format!(
        r#"<shape type="sphere"><point name="center" value="{cx}, {h}, 0"/><float name="radius" value="{r}"/>
            <bsdf type="diffuse"><float name="reflectance" value="0"/></bsdf>
            <emitter type="area"><rgb name="radiance" value="{l}"/></emitter></shape>"#
    );
    let want = |x: f64, z: f64| {
        let d2 = (x - cx).powi(2) + h * h + z * z;
        [RHO * l * r * r * h / d2.powf(1.5); 3]
    };
    check("sphere", &light, want, [0.0; 3]);
}
