//! Radiosity through the command line: `--integrator radiosity` and `<integrator
//! type="radiosity">` both work, options reach the solver, and bad options are input errors.
//! The solver's own correctness (closed-form sphere, energy balance, convergence with patch size)
//! is tested in crates/pt-radiosity/tests/validation.rs.

use crate::common;

use common::*;

#[test]
fn radiosity_cornell_box_from_the_command_line() {
    let dir = scratch("radiosity_cli");
    let scene = repo().join("scenes/cornell-box.xml");
    let args = [
        "--integrator",
        "radiosity",
        "--patch-size",
        "0.25",
        "--rays-per-patch",
        "256",
        "--spp",
        "4",
        "--radiosity-solver",
        "progressive",
    ];
    let (img, _) = render(&scene, &dir, "rad", &args);
    let (reference, _) = reference("cornell-box");
    let m = pt_image::metrics::compare(&img, &reference).unwrap();
    // Discretisation bias, not noise: at this patch size the crate's study measured relMSE
    // 0.0045 (smoothed display); 0.01 catches a broken solve (no indirect light gives ~0.05).
    assert!(m.relmse_all < 0.01, "relMSE {}", m.relmse_all);
    for r in m.mean_ratio {
        // Energy is conserved up to form-factor noise: the image mean is within 2%.
        assert!((r - 1.0).abs() < 0.02, "mean ratio {r}");
    }
}

#[test]
fn radiosity_integrator_from_the_scene_file_and_bad_options() {
    let dir = scratch("radiosity_xml");
    let xml = std::fs::read_to_string(repo().join("scenes/cornell-box.xml")).unwrap();
    let start = xml.find(r#"<integrator type="path">"#).unwrap();
    let end = xml[start..].find("</integrator>").unwrap() + start + "</integrator>".len();
    let radiosity = r#"<integrator type="radiosity"><float name="patch_size" value="0.5"/><integer name="rays_per_patch" value="64"/><string name="display" value="constant"/></integrator>"#;
    let xml = format!("{}{radiosity}{}", &xml[..start], &xml[end..]);
    let path = dir.join("rad.xml");
    std::fs::write(&path, &xml).unwrap();
    let out = dir.join("rad.exr");
    let o = pt(&[
        "render",
        path.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--spp",
        "1",
        "--width",
        "32",
        "--height",
        "32",
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(stderr.contains("radiosity:"), "{stderr}");
    let (_, meta) = pt_image::read_exr(&out).unwrap();
    assert!(
        meta.extra
            .iter()
            .any(|(k, v)| k == "integrator" && v == "radiosity"),
        "{:?}",
        meta.extra
    );
    // A bad solver name is an input error: on the command line naming the option, in the
    // scene naming the integrator's property; no output either way.
    let out2 = dir.join("bad.exr");
    let o = pt(&[
        "render",
        path.to_str().unwrap(),
        "-o",
        out2.to_str().unwrap(),
        "--radiosity-solver",
        "newton",
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("--radiosity-solver")
            && stderr.contains("jacobi, gauss_seidel, progressive"),
        "{stderr}"
    );
    assert!(!out2.exists());
    let bad = xml.replace(
        r#"<string name="display" value="constant"/>"#,
        r#"<string name="solver" value="newton"/>"#,
    );
    let bad_path = dir.join("bad.xml");
    std::fs::write(&bad_path, bad).unwrap();
    let o = pt(&[
        "render",
        bad_path.to_str().unwrap(),
        "-o",
        out2.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("string name=\"solver\"") && stderr.contains("unknown solver 'newton'"),
        "{stderr}"
    );
    assert!(!out2.exists());
}

/// Where radiosity fails: on scenes/cornell-glass.xml (a mirror ball and a glass ball) it treats
/// both as grey diffuse and cannot make the caustic or the reflections, so its error against the
/// Mitsuba reference stays at a floor that finer patches do not lower (measured relMSE 0.041 at
/// 978, 2952 and 9948 patches), while path tracing keeps converging (0.011 at 256 spp, 0.0032 at
/// 1024). The test pins that regime down: glossy relMSE above 0.02 at two patch sizes that differ
/// by 2x in edge length, and within 10% of each other (on the diffuse box the same sizes give
/// 0.0057 and 0.0029: there refinement helps).
#[test]
fn radiosity_fails_on_glossy_surfaces_by_a_bias_floor() {
    let dir = scratch("radiosity_glossy");
    let scene = repo().join("scenes/cornell-glass.xml");
    let (reference, _) = reference("cornell-glass");
    let mut errs = Vec::new();
    for h in ["0.35", "0.18"] {
        let args = [
            "--integrator",
            "radiosity",
            "--patch-size",
            h,
            "--rays-per-patch",
            "256",
            "--spp",
            "4",
        ];
        let (img, _) = render(&scene, &dir, &format!("glass_{h}"), &args);
        errs.push(
            pt_image::metrics::compare(&img, &reference)
                .unwrap()
                .relmse_all,
        );
    }
    eprintln!("radiosity on cornell-glass: relMSE {errs:?}");
    assert!(errs.iter().all(|&e| e > 0.02), "{errs:?}");
    assert!(
        (errs[0] / errs[1] - 1.0).abs() < 0.1,
        "finer patches should not help: {errs:?}"
    );
}

/// Spectral radiosity: a scene with tabulated spectra is solved per wavelength bin (24 bins over
/// 360-830 nm) and converted through the CIE observer, like the spectral film. Against Mitsuba's
/// spectral reference (rescaled by its y-bar normalisation, see tests/common), the walls (pixels
/// away from the light, whose edge pixels carry the display's own error) agree within 2% per
/// channel; measured 0.999 / 0.998 / 0.991 at this patch size. Discretisation and form-factor
/// noise, not Monte Carlo noise, set the margin; 2% catches a wrong film weight or a solve in the
/// wrong bins (12 bins already gave 0.982 in red).
#[test]
fn spectral_radiosity_matches_the_spectral_reference_on_the_walls() {
    let dir = scratch("radiosity_spectral");
    let scene = repo().join("scenes/cornell-spectral.xml");
    let args = [
        "--integrator",
        "radiosity",
        "--patch-size",
        "0.18",
        "--rays-per-patch",
        "512",
        "--spp",
        "4",
    ];
    let (img, _) = render(&scene, &dir, "spectral", &args);
    let (reference, _) = reference("cornell-spectral");
    let (mut a, mut r) = ([0.0f64; 3], [0.0f64; 3]);
    for (p, q) in img.data.iter().zip(&reference.data) {
        if q.iter().fold(0.0f32, |m, v| m.max(*v)) < 3.0 {
            for c in 0..3 {
                a[c] += p[c] as f64;
                r[c] += q[c] as f64;
            }
        }
    }
    let ratio: Vec<f64> = (0..3).map(|c| a[c] / r[c]).collect();
    eprintln!("spectral radiosity / reference on the walls: {ratio:?}");
    assert!(ratio.iter().all(|x| (x - 1.0).abs() < 0.02), "{ratio:?}");
}
