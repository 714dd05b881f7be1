//! Tests of the lights: sampling against pdfs, spectral environment maps against Mitsuba.

use super::*;
use pt_math::{Distribution1D, Mat3};

/// Uniform numbers in [0, 1) from a 64-bit LCG (Knuth's MMIX constants) seeded with `seed`:
/// deterministic streams for the sampling tests (the light tree's too).
pub(super) fn lcg(mut s: u64) -> impl FnMut() -> f32 {
    move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 40) as f32) / (1u64 << 24) as f32
    }
}

/// The path's four wavelengths all at `l` nm.
fn at(l: f32) -> SampledWavelengths {
    SampledWavelengths::sample_visible(0.5).with_lambda(pt_math::Vec4::splat(l))
}

#[test]
fn spectral_envmap_matches_mitsuba_probe() {
    // A 4x3 map with columns of rgb (1, 0.5, 0.2), (10, 10, 10), (0.1, 0.2, 0.8), (2, 1, 1),
    // evaluated halfway between the first two column centres (u = 0.25, v = 0.5). Mitsuba
    // 3.9.1 scalar_spectral's envmap (times its D65) gave 3.99998, 4.43127, 4.58698 at 450,
    // 550, 650 nm: the product of the interpolated sigmoid values and the interpolated
    // scales. Interpolating the products instead gives 6.046, 5.535, 4.472 (+51%, +25%,
    // -2.5%). 1% allows for Mitsuba's tabulated coefficients against pt's exact fit.
    let cols = [
        [1.0f32, 0.5, 0.2],
        [10.0, 10.0, 10.0],
        [0.1, 0.2, 0.8],
        [2.0, 1.0, 1.0],
    ];
    let texels: Vec<[f32; 3]> = (0..12).map(|i| cols[i % 4]).collect();
    let mut e = EnvMap::new(4, 3, texels, Mat3::IDENTITY).unwrap();
    e.upsample();
    let (dir, _) = e.uv_to_dir(Vec2::new(0.25, 0.5));
    for (l, mitsuba) in [(450.0f32, 3.99998f32), (550.0, 4.43127), (650.0, 4.58698)] {
        let v = e.radiance(dir, &at(l)).0.x;
        assert!(
            (v / mitsuba - 1.0).abs() < 0.01,
            "{l} nm: {v} vs Mitsuba {mitsuba}"
        );
    }
}

#[test]
fn spectral_envmap_sampling_is_consistent_with_its_pdf() {
    // Spectral radiance with the RGB-luminance sampling distribution: every sample's pdf must
    // equal pdf(dir), and E[L / pdf] must equal the integral of L over the sphere (computed
    // by midpoint quadrature in (u, v) with the Jacobian 2 pi^2 sin(pi v)). Radiance where
    // the pdf is 0, or a pdf that does not match the sampling, biases the estimate. The map
    // has black texels, a bright spot and colours; threshold 5 standard errors of the
    // estimate (from the samples), plus 1e-3 relative for the quadrature.
    let (w, h) = (8usize, 6usize);
    let texels: Vec<[f32; 3]> = (0..w * h)
        .map(|i| match (i % w, i / w) {
            (x, _) if x < 2 => [0.0; 3],
            (5, 2) => [40.0, 30.0, 5.0],
            (x, y) => [0.1 + 0.1 * x as f32, 0.2 + 0.1 * y as f32, 0.6],
        })
        .collect();
    let mut e = EnvMap::new(w, h, texels, Mat3::from_rotation_y(0.7)).unwrap();
    e.upsample();
    let lambda = at(520.0);
    let n = 200_000;
    let mut rnd = lcg(7);
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    let mut boundary = 0;
    for _ in 0..n {
        let Some((dir, l, pdf)) = e.sample(Vec2::new(rnd(), rnd()), &lambda) else {
            continue;
        };
        // A sample on a cell boundary can come back (dir -> uv in f32) in the neighbouring
        // cell, whose pdf differs: allowed for a few; a wrong pdf would mismatch everywhere.
        if (e.pdf(dir) - pdf).abs() > 1e-3 * pdf {
            boundary += 1;
        }
        // Same lookup up to the uv -> direction -> uv round trip in f32.
        let back = e.radiance(dir, &lambda);
        assert!(
            (l.0 - back.0).abs().max_element() <= 1e-4 * back.0.abs().max_element().max(1e-3),
            "{l:?} vs {back:?}"
        );
        let f = (l.0.x / pdf) as f64;
        sum += f;
        sum2 += f * f;
    }
    assert!(
        boundary < n / 1000,
        "{boundary} of {n} samples have a pdf that pdf(dir) does not reproduce"
    );
    let mean = sum / n as f64;
    let se = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
    let m = 1000;
    let mut quad = 0.0f64;
    for j in 0..m {
        let v = (j as f32 + 0.5) / m as f32;
        for i in 0..2 * m {
            let u = (i as f32 + 0.5) / (2 * m) as f32;
            let (dir, sin_t) = e.uv_to_dir(Vec2::new(u, v));
            quad +=
                (e.radiance(dir, &lambda).0.x * 2.0 * PI * PI * sin_t) as f64 / (2 * m * m) as f64;
        }
    }
    assert!(
        (mean - quad).abs() < 5.0 * se + 1e-3 * quad,
        "E[L/pdf] {mean} +- {se} vs integral {quad}"
    );
}

#[test]
fn sampled_pdf_matches_pdf_query() {
    let tri = |a: Vec3, b: Vec3, c: Vec3| {
        let n = (b - a).cross(c - a).normalize();
        LightTriangle {
            p: [a, b, c],
            n: [n; 3],
            uv: [Vec2::ZERO; 3],
        }
    };
    // A 2 x 1 rectangle at y = 1 facing down, split into two triangles of equal area.
    let tris = vec![
        tri(
            Vec3::new(-1.0, 1.0, -0.5),
            Vec3::new(1.0, 1.0, -0.5),
            Vec3::new(1.0, 1.0, 0.5),
        ),
        tri(
            Vec3::new(-1.0, 1.0, -0.5),
            Vec3::new(1.0, 1.0, 0.5),
            Vec3::new(-1.0, 1.0, 0.5),
        ),
    ];
    assert!(
        tris[0].n.iter().all(|n| (n.y + 1.0).abs() < 1e-6),
        "faces down"
    );
    // The same rectangle as a parallelogram.
    let (v0, e1, e2) = (
        Vec3::new(-1.0, 1.0, -0.5),
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
    );
    let parallelogram = LightShape::Parallelogram {
        v0,
        e1,
        e2,
        n: e1.cross(e2).normalize(),
        uv: [Vec2::ZERO, Vec2::X, Vec2::Y],
    };
    assert_eq!(e1.cross(e2).normalize(), -Vec3::Y, "faces down");
    for shape in [
        LightShape::Mesh {
            tris,
            distr: Distribution1D::new(&[1.0, 1.0]).unwrap(),
        },
        parallelogram,
    ] {
        solid_angle_matches_quadrature(AreaLight {
            radiance: crate::texture::Texture::rgb([1.0; 3]),
            shape,
            area: 2.0,
        });
    }
}

/// For the 2 x 1 rectangle at y = 1 facing down that `light` is: the solid angle from a
/// point below estimated with light samples, E[1/pdf], against quadrature; and every
/// sample's pdf against [`AreaLight::pdf`].
fn solid_angle_matches_quadrature(light: AreaLight) {
    let x = Vec3::new(0.2, 0.0, 0.1);
    // Estimate the solid angle subtended: E[1/pdf] = solid angle. Compare with the value from
    // dense midpoint quadrature of cos/d^2 over the rectangle.
    let n = 200_000;
    let mut rnd = lcg(99);
    let mut est = 0.0f64;
    let lambda = SampledWavelengths::sample_visible(0.5);
    for _ in 0..n {
        let ls = light
            .sample(x, rnd(), Vec2::new(rnd(), rnd()), &lambda)
            .unwrap();
        assert!((light.pdf(x, ls.p, ls.n) - ls.pdf).abs() <= 1e-4 * ls.pdf);
        assert!(!ls.radiance.is_black(), "front side faces x");
        est += 1.0 / ls.pdf as f64;
    }
    est /= n as f64;
    let m = 400;
    let mut quad = 0.0f64;
    for i in 0..m {
        for j in 0..m {
            let p = Vec3::new(
                -1.0 + 2.0 * (i as f32 + 0.5) / m as f32,
                1.0,
                -0.5 + (j as f32 + 0.5) / m as f32,
            );
            let d = p - x;
            let cos = d.y / d.length();
            quad += (cos / d.length_squared()) as f64 * (2.0 / (m * m) as f64);
        }
    }
    // Monte Carlo relative error of 1/pdf here is ~0.3 / sqrt(2e5) < 1e-3; 5e-3 is 5 sigma.
    assert!((est - quad).abs() / quad < 5e-3, "{est} vs {quad}");
}

/// A cylinder light seen from a point beside it, off its middle: E[front / pdf] over light
/// samples (the solid angle of the part of its surface whose front faces the point) against a
/// midpoint quadrature of max(0, cos) / d^2 over (z, phi), with every sample's pdf against
/// [`AreaLight::pdf`] and every sample on the surface. Once with the normals out (the near
/// side faces the point), once flipped (the inside of the far side does): a sampler that
/// ignored the flip, put its points off the surface or mis-scaled its pdf fails.
#[test]
fn cylinder_light_matches_quadrature() {
    let frame = pt_math::Mat3::from_rotation_x(0.4) * pt_math::Mat3::from_rotation_z(1.1);
    let (p0, radius, length) = (Vec3::new(0.3, -0.2, 0.1), 0.5, 2.0);
    let x = p0 + frame * Vec3::new(1.7, 0.4, 1.5);
    let lambda = SampledWavelengths::sample_visible(0.5);
    for flip in [false, true] {
        let light = AreaLight {
            radiance: crate::texture::Texture::rgb([1.0; 3]),
            shape: LightShape::Cylinder {
                p0,
                frame,
                radius,
                length,
                flip,
            },
            area: std::f32::consts::TAU * radius * length,
        };
        let n = 200_000;
        let mut rnd = lcg(7);
        let mut est = 0.0f64;
        for _ in 0..n {
            let ls = light
                .sample(x, rnd(), Vec2::new(rnd(), rnd()), &lambda)
                .unwrap();
            // 1 / pdf = |cos| A / d^2: its rounding is that of the cosine, absolute, so
            // compared as 1 / pdf on the scale A / d^2 (relative pdfs diverge at grazing).
            let q = light.pdf(x, ls.p, ls.n);
            let scale = light.area / (ls.dist * ls.dist);
            assert!(
                (1.0 / q - 1.0 / ls.pdf).abs() <= 1e-5 * scale,
                "{q} vs {} at cos {}",
                ls.pdf,
                ls.n.dot(ls.wi)
            );
            let local = frame.transpose() * (ls.p - p0);
            let rho = (local.x * local.x + local.y * local.y).sqrt();
            assert!((rho - radius).abs() < 1e-5 && (-1e-5..=length + 1e-5).contains(&local.z));
            if !ls.radiance.is_black() {
                est += 1.0 / ls.pdf as f64;
            }
        }
        est /= n as f64;
        let (nz, nphi) = (400, 800);
        let mut quad = 0.0f64;
        for i in 0..nz {
            for j in 0..nphi {
                let z = length * (i as f32 + 0.5) / nz as f32;
                let phi = std::f32::consts::TAU * (j as f32 + 0.5) / nphi as f32;
                let out = frame * Vec3::new(phi.cos(), phi.sin(), 0.0);
                let p = p0 + out * radius + frame.z_axis * z;
                let front = if flip { -out } else { out };
                let d = x - p;
                let cos = front.dot(d) / d.length();
                let da = light.area / (nz * nphi) as f32;
                quad += (cos.max(0.0) / d.length_squared() * da) as f64;
            }
        }
        // As for the rectangle: the relative error of the estimate is ~1 / sqrt(2e5) times
        // the spread of front / pdf (below 1 here); 5e-3 is over 5 sigma.
        assert!(
            (est - quad).abs() / quad < 5e-3,
            "flip {flip}: {est} vs {quad}"
        );
    }
}

/// A disk light (an ellipse: sheared, unequal axes, tilted) seen from a point off its axis:
/// E[front / pdf] over light samples (the solid angle of the disk if its front faces the point,
/// else 0) against a midpoint quadrature of cos / d^2 over the disk in polar coordinates, with
/// every sample's pdf against [`AreaLight::pdf`], every sample inside the disk and its texture
/// coordinates (r, phi / 2 pi) those of its point. Both sides: a sampler that ignored the
/// front side, left the ellipse or mis-scaled its pdf (the area of an ellipse is pi |a x b|,
/// not pi |a| |b|) fails.
#[test]
fn disk_light_matches_quadrature() {
    let (center, a, b) = (
        Vec3::new(0.2, 1.0, -0.1),
        Vec3::new(0.8, 0.1, 0.0),
        Vec3::new(0.3, 0.0, 0.5),
    );
    let x = Vec3::new(-0.3, -0.5, 0.4);
    let lambda = SampledWavelengths::sample_visible(0.5);
    let toward = a.cross(b).normalize();
    assert!(toward.dot(x - center) > 0.0, "a x b faces x");
    for normal in [toward, -toward] {
        let disk = pt_scene::Disk {
            center,
            axes: [a, b],
            normal,
        };
        let light = AreaLight {
            radiance: crate::texture::Texture::rgb([1.0; 3]),
            shape: LightShape::Disk(disk),
            area: disk.area(),
        };
        let to_local = pt_math::Mat3::from_cols(a, b, toward).inverse();
        let n = 200_000;
        let mut rnd = lcg(11);
        let mut est = 0.0f64;
        for _ in 0..n {
            let (u_sel, u) = (rnd(), Vec2::new(rnd(), rnd()));
            let ls = light.sample(x, u_sel, u, &lambda).unwrap();
            let q = light.pdf(x, ls.p, ls.n);
            assert!((q - ls.pdf).abs() <= 1e-4 * ls.pdf, "{q} vs {}", ls.pdf);
            let local = to_local * (ls.p - center);
            assert!(local.z.abs() < 1e-5 && local.truncate().length() <= 1.0 + 1e-5);
            let (_, _, uv) = light.sample_point(u_sel, u);
            let phi = uv.y * std::f32::consts::TAU;
            let expected = Vec2::new(phi.cos(), phi.sin()) * uv.x;
            assert!(
                (expected - local.truncate()).length() < 1e-4,
                "{uv} at {local}"
            );
            assert!((0.0..1.0).contains(&uv.y));
            if !ls.radiance.is_black() {
                est += 1.0 / ls.pdf as f64;
            }
        }
        est /= n as f64;
        let (nr, nphi) = (400, 800);
        let mut quad = 0.0f64;
        for i in 0..nr {
            for j in 0..nphi {
                let r = (i as f32 + 0.5) / nr as f32;
                let phi = std::f32::consts::TAU * (j as f32 + 0.5) / nphi as f32;
                let p = center + a * (r * phi.cos()) + b * (r * phi.sin());
                let d = x - p;
                let cos = normal.dot(d) / d.length();
                // dA = |a x b| r dr dphi.
                let da = a.cross(b).length() * r / nr as f32 * std::f32::consts::TAU / nphi as f32;
                quad += (cos.max(0.0) / d.length_squared() * da) as f64;
            }
        }
        if normal != toward {
            assert_eq!(est, 0.0, "the back of the disk emits nothing");
            assert_eq!(quad, 0.0);
        } else {
            // As for the rectangle: the estimate's relative error is ~1 / sqrt(2e5) times the
            // spread of 1 / pdf (below 1 here); 5e-3 is over 5 sigma.
            assert!((est - quad).abs() / quad < 5e-3, "{est} vs {quad}");
        }
    }
}

/// Rays leaving each kind of light carry, on average, the light's power
/// (`Light::sample_emission`'s weight is Le cos / (p_pos p_dir)): 4 pi I for a point light,
/// 2 pi (1 - cos c) I for a hard spot (beam width = cutoff), pi A L for an area light, pi R^2 E
/// for a directional light over the disk of radius R, and pi R^2 times 4 pi L for a constant
/// environment. The directions stay where the light sends light: inside the spot's cone, in
/// the area light's front hemisphere, along -to_light for the directional light, and every
/// distant ray starts on its disk at distance R from the centre. 2^16 samples; every weight
/// here is constant but for the spot (constant too: hard cone) and area light (constant
/// radiance), so the means are exact to rounding: 1e-3 relative.
#[test]
fn emitted_rays_carry_the_lights_power() {
    use std::f32::consts::PI;
    let lambda = SampledWavelengths::sample_visible(0.5);
    let rgb = |v: f32| crate::texture::ConstantSpectrum::Rgb(SampledSpectrum::from_rgb([v; 3]));
    let bounds = (Vec3::new(0.5, -1.0, 2.0), 3.0);
    let spot_frame = Frame::from_normal(Vec3::new(0.0, -1.0, 0.2).normalize());
    let cutoff = 0.4f32;
    let to_light = Vec3::new(0.3, 1.0, -0.2).normalize();
    let par_n = Vec3::new(0.0, -1.0, 0.0);
    let lights: Vec<(Light, f32)> = vec![
        (
            Light::Point {
                position: Vec3::new(1.0, 2.0, 3.0),
                intensity: rgb(2.0),
                profile: None,
            },
            4.0 * PI * 2.0,
        ),
        (
            Light::Spot {
                position: Vec3::ZERO,
                frame: spot_frame,
                intensity: rgb(3.0),
                cone: SpotCone {
                    cos_cutoff: cutoff.cos(),
                    cutoff,
                    beam_width: cutoff,
                },
                texture: None,
                profile: None,
            },
            2.0 * PI * (1.0 - cutoff.cos()) * 3.0,
        ),
        (
            Light::Area(AreaLight {
                radiance: crate::texture::Texture::rgb([1.5; 3]),
                shape: LightShape::Parallelogram {
                    v0: Vec3::new(-1.0, 1.0, -0.5),
                    e1: Vec3::new(2.0, 0.0, 0.0),
                    e2: Vec3::new(0.0, 0.0, 1.0),
                    n: par_n,
                    uv: [Vec2::ZERO, Vec2::X, Vec2::Y],
                },
                area: 2.0,
            }),
            PI * 2.0 * 1.5,
        ),
        (
            Light::Directional {
                to_light,
                irradiance: rgb(0.7),
            },
            PI * 9.0 * 0.7,
        ),
        (
            Light::Constant { radiance: rgb(0.2) },
            PI * 9.0 * 4.0 * PI * 0.2,
        ),
    ];
    for (light, power) in &lights {
        let mut u = lcg(11);
        let n = 1 << 16;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let (us, up, ud) = (u(), Vec2::new(u(), u()), Vec2::new(u(), u()));
            let Some(e) = light.sample_emission(us, up, ud, &lambda, bounds) else {
                continue;
            };
            sum += f64::from(e.weight.0.x);
            // The densities the bidirectional methods weigh strategies with are those the
            // ray was drawn with.
            let (pdf_pos, pdf_dir) = light.emission_pdf(e.normal, e.ray.dir, bounds);
            assert!((pdf_pos / e.pdf_pos - 1.0).abs() < 1e-4, "{light:?}");
            assert!((pdf_dir / e.pdf_dir - 1.0).abs() < 1e-3, "{light:?}");
            match light {
                Light::Spot { frame, .. } => {
                    assert!(frame.n.dot(e.ray.dir) >= cutoff.cos() - 1e-5)
                }
                Light::Area(_) => assert!(e.ray.dir.dot(par_n) > 0.0),
                Light::Directional { .. } => {
                    assert!((e.ray.dir + to_light).length() < 1e-5);
                }
                _ => {}
            }
            if light.is_infinite() || matches!(light, Light::Directional { .. }) {
                // On the disk: distance R from the centre along the direction, within R of
                // the axis.
                let rel = e.ray.origin - bounds.0;
                let along = rel.dot(-e.ray.dir);
                assert!((along - bounds.1).abs() < 1e-4, "{along}");
                assert!((rel - along * -e.ray.dir).length() <= bounds.1 * 1.0001);
            }
        }
        let mean = sum / f64::from(n);
        assert!(
            (mean / f64::from(*power) - 1.0).abs() < 1e-3,
            "{light:?}: {mean} vs {power}"
        );
    }
}

/// Point and spot lights with an IES profile: rays leave with the densities `emission_pdf`
/// reports (what the bidirectional methods weigh with), never outside a spot's cone, and their
/// mean weight is the light's power (intensity times the profile's integral, with the
/// falloff): 2^16 rays, five standard errors (the weights vary: about 0.5% here).
#[test]
fn profiled_lights_emit_their_power_with_consistent_densities() {
    let text = "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 5 3 1 2 0 0 0\n1 1 10\n0 20 40 60 90\n0 45 90\n100 90 60 20 0\n100 80 40 10 0\n100 70 30 5 0\n";
    let table = pt_scene::ies::parse_ies(text).unwrap();
    let rot = pt_math::Mat3::from_rotation_x(2.5);
    let lambda = SampledWavelengths::sample_visible(0.5);
    let rgb = |v: f32| crate::texture::ConstantSpectrum::Rgb(SampledSpectrum::from_rgb([v; 3]));
    let cutoff = 50f32.to_radians();
    let cone = SpotCone {
        cos_cutoff: cutoff.cos(),
        cutoff,
        beam_width: 30f32.to_radians(),
    };
    let profile = |cone: Option<&SpotCone>| {
        Some(Box::new(
            super::IntensityProfile::new(&table, 0.01, rot, cone).unwrap(),
        ))
    };
    let axis = rot * Vec3::Z;
    let lights = [
        Light::Point {
            position: Vec3::ONE,
            intensity: rgb(2.0),
            profile: profile(None),
        },
        Light::Spot {
            position: Vec3::ONE,
            frame: Frame::from_normal(axis),
            intensity: rgb(2.0),
            cone,
            texture: None,
            profile: profile(Some(&cone)),
        },
    ];
    let bounds = (Vec3::ZERO, 3.0);
    for light in &lights {
        // The power by quadrature over the sphere of what sample() returns towards each
        // direction (the falloff included).
        let quad = super::profile::tests::over_sphere(500, |d| {
            let ls = light
                .sample(Vec3::ONE - d, 0.5, Vec2::ZERO, &lambda)
                .unwrap();
            ls.radiance.0.x
        });
        let mut u = lcg(5);
        let m = 1 << 16;
        let (mut s1, mut s2) = (0.0f64, 0.0f64);
        for _ in 0..m {
            let (us, up, ud) = (u(), Vec2::new(u(), u()), Vec2::new(u(), u()));
            let Some(e) = light.sample_emission(us, up, ud, &lambda, bounds) else {
                continue;
            };
            let w = f64::from(e.weight.0.x);
            s1 += w;
            s2 += w * w;
            let (_, pdf_dir) = light.emission_pdf(e.normal, e.ray.dir, bounds);
            assert!(
                (pdf_dir / e.pdf_dir - 1.0).abs() < 1e-3,
                "{pdf_dir} vs {}",
                e.pdf_dir
            );
            if matches!(light, Light::Spot { .. }) {
                assert!(axis.dot(e.ray.dir) >= cutoff.cos() - 1e-4);
            }
        }
        let mean = s1 / f64::from(m);
        let se = ((s2 / f64::from(m) - mean * mean) / f64::from(m)).sqrt();
        assert!(
            5.0 * se < 0.02 * quad,
            "too noisy to see a 2% error: {se} of {quad}"
        );
        assert!(
            (mean - quad).abs() < 5.0 * se + 2e-3 * quad,
            "{light:?}: mean weight {mean} +- {se}, power {quad}"
        );
        // Light selection's power estimate: intensity luminance times the integral (exact
        // for the point light; the spot's falloff taken per cell, within 2%).
        let power = f64::from(light.power(1.0));
        assert!(
            (power - quad).abs() < 0.02 * quad,
            "power {power} vs {quad}"
        );
    }
}

/// Sphere lights sampled in lanes give every lane what one lane gives alone, bit for bit
/// (spheres of different sizes and places, seen from outside, from inside, and from a point
/// of the surface, which samples by area instead), and the samples lie on the spheres.
#[test]
fn sphere_cones_in_lanes_match_one_lane_bit_for_bit() {
    use pt_math::lanes::V3;
    let centers = V3::<8>::from_fn(|k| Vec3::new(k as f32 - 3.0, 4.0, 8.0 - k as f32));
    let radius: [f32; 8] = std::array::from_fn(|k| 0.03 + 0.4 * k as f32);
    let x = V3::<8>::from_fn(|k| match k {
        // Inside the sphere, and on its surface.
        2 => centers.get(2),
        5 => centers.get(5) + Vec3::new(0.0, radius[5], 0.0),
        _ => Vec3::new(0.1 * k as f32, -1.0, 0.5),
    });
    let u0 = [0.1, 0.5, 0.9, 0.3, 0.7, 0.2, 0.99, 0.0];
    let u1 = [0.8, 0.25, 0.6, 0.1, 0.4, 0.95, 0.5, 0.33];
    let c8 = sphere_cone_lanes(&centers, &radius, &x, &u0, &u1);
    let bits = |v: Vec3| v.to_array().map(f32::to_bits);
    for k in 0..8 {
        let c1 = sphere_cone_lanes(
            &V3::<1>::splat(centers.get(k)),
            &[radius[k]],
            &V3::splat(x.get(k)),
            &[u0[k]],
            &[u1[k]],
        );
        assert_eq!(
            (c8.outside[k], c8.ok[k]),
            (c1.outside[0], c1.ok[0]),
            "lane {k}"
        );
        assert_eq!(c8.outside[k], k != 2 && k != 5, "lane {k}");
        if !c1.ok[0] {
            continue;
        }
        assert_eq!(bits(c8.p.get(k)), bits(c1.p.get(0)), "lane {k}");
        assert_eq!(bits(c8.n_out.get(k)), bits(c1.n_out.get(0)), "lane {k}");
        assert_eq!(bits(c8.wi.get(k)), bits(c1.wi.get(0)), "lane {k}");
        assert_eq!(c8.dist[k].to_bits(), c1.dist[0].to_bits(), "lane {k}");
        assert_eq!(c8.pdf[k].to_bits(), c1.pdf[0].to_bits(), "lane {k}");
        // On the sphere, on the side facing x.
        let r = (c8.p.get(k) - centers.get(k)).length();
        assert!(
            (r - radius[k]).abs() < 1e-4 * (1.0 + radius[k]),
            "lane {k}: {r}"
        );
        assert!(
            c8.n_out.get(k).dot(x.get(k) - c8.p.get(k)) > 0.0,
            "lane {k}"
        );
    }
}
