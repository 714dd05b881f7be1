//! The analysis commands (`pt lobes`, `pt stability`, `pt atlas`, `pt converge`) end to end at
//! small settings: exit codes, the files each writes and their shape, and bad input refused
//! with exit code 2 and nothing written. What the numbers mean is tested in `pt-lab` beside
//! the code (closed forms, chi-square wiring, the atlases' conclusions).

use crate::common;

use common::*;
use std::path::Path;

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

#[test]
fn lobes_writes_the_figure_and_the_csv() {
    let dir = scratch("analysis_lobes");
    let (svg, png, csv) = (dir.join("l.svg"), dir.join("l.png"), dir.join("l.csv"));
    for out in [&svg, &png] {
        let o = pt(&[
            "lobes",
            "roughconductor alpha=0.3 material=Au",
            "--compare",
            "dielectric eta=1.5",
            "--compare",
            "twosided diffuse reflectance=0.4",
            "--theta-i",
            "0,45",
            "--albedo-samples",
            "500",
            "--hist-samples",
            "20000",
            "-o",
            s(out),
            "--csv",
            s(&csv),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        // One sampling line per smooth model (the dielectric's lobes are deltas).
        assert_eq!(stderr(&o).matches("chi2/dof").count(), 2, "{}", stderr(&o));
    }
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<svg"));
    assert!(std::fs::read(&png).unwrap().starts_with(b"\x89PNG"));
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(text.starts_with("panel,series,theta_i,theta_o,phi,f,pdf,albedo,albedo_stderr,hist\n"));
    for panel in ["lobe,", "albedo,", "histogram,", "hemisphere,"] {
        assert!(
            text.lines().any(|l| l.starts_with(panel)),
            "no {panel} rows"
        );
    }
    assert!(text.contains("\"dielectric eta=1.5\""));
}

#[test]
fn lobes_refuses_bad_input_with_exit_code_2_and_writes_nothing() {
    let dir = scratch("analysis_lobes_bad");
    let out = dir.join("x.svg");
    for (args, message) in [
        (vec!["velvet"], "unknown model 'velvet'"),
        (
            vec!["orennayar foo=1"],
            "orennayar: unknown parameter 'foo' (parameters: reflectance, sigma, variant)",
        ),
        (vec!["orennayar sigma=-1"], "sigma must be in [0, "),
        (
            vec!["roughconductor material=unobtainium"],
            "unknown conductor 'unobtainium'",
        ),
        (
            vec!["diffuse reflectance=2"],
            "reflectance must be one number or r,g,b, each in [0, 1]",
        ),
        (
            vec!["dielectric eta=1.5 int_ior=1.3"],
            "give either eta or int_ior/ext_ior",
        ),
        (
            vec!["diffuse", "--theta-i", "95"],
            "--theta-i must be in [0, 90) degrees, got 95",
        ),
        (
            vec!["diffuse", "--compare", "foo"],
            "--compare \"foo\": unknown model 'foo'",
        ),
    ] {
        let mut a = vec!["lobes"];
        a.extend(args);
        a.extend(["-o", s(&out)]);
        let o = pt(&a);
        assert_eq!(o.status.code(), Some(2), "{a:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(message), "{a:?}: {}", stderr(&o));
        assert!(!out.exists(), "{a:?} left a file");
    }
    let o = pt(&["lobes", "diffuse", "-o", s(&dir.join("x.txt"))]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("the figure must be .svg or .png"));
}

#[test]
fn stability_writes_the_csv_report_and_charts() {
    let dir = scratch("analysis_stability");
    let o = pt(&[
        "stability",
        "--out",
        s(&dir),
        "--samples",
        "100",
        "--chi2-samples",
        "0",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = std::fs::read_to_string(dir.join("stability.csv")).unwrap();
    assert!(csv.starts_with("family,param_name,param,detail,in_range,energy_bound,theta_deg,side,"));
    // 687 configurations x 8 angles, both sides for transmissive models: 7488 probes.
    assert_eq!(csv.lines().count(), 1 + 7488);
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    for section in [
        "# BSDF stability report",
        "## Findings",
        "## Firefly clamp",
        "(albedo.svg)",
        "(clamp.svg)",
    ] {
        assert!(md.contains(section), "report.md lacks {section}");
    }
    for f in ["albedo.svg", "albedo.png", "clamp.svg", "clamp.png"] {
        assert!(dir.join(f).is_file(), "{f} missing");
    }
    let o = pt(&["stability", "--out", s(&dir.join("no")), "--samples", "10"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--samples must be at least 100, got 10"));
    assert!(!dir.join("no").exists());
}

#[test]
fn atlas_writes_the_report_and_the_charts_of_a_study() {
    let dir = scratch("analysis_atlas");
    let refs = repo().join("references/atlas");
    let o = pt(&[
        "atlas",
        "--out",
        s(&dir),
        "--references",
        s(&refs),
        "--only",
        "veach",
        "--equal",
        "spp",
        "--spp",
        "1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("atlas: Veach done in"),
        "{}",
        stderr(&o)
    );
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(md.starts_with("# Method failure atlas"));
    assert!(md.contains("## Direct light: BSDF sampling, light sampling and MIS (Veach)"));
    assert!(md.contains("Reference: Mitsuba 3"), "{md}");
    assert!(md.contains("(atlas-veach.svg)"));
    assert!(dir.join("atlas-veach.svg").is_file() && dir.join("atlas-veach.png").is_file());
    assert!(!dir.join("atlas-caustic.svg").exists());
    let o = pt(&["atlas", "--out", s(&dir), "--spp", "0"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--spp must be at least 1"));
}

#[test]
fn converge_measures_each_curve_and_writes_its_files() {
    let dir = scratch("analysis_converge");
    let o = pt(&[
        "converge",
        "scenes/cornell-box.xml",
        "--reference",
        "references/cornell-box.exr",
        "--spp",
        "2,1",
        "--strategy",
        "mis,bsdf",
        "--out",
        s(&dir),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = std::fs::read_to_string(dir.join("converge.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().collect();
    assert_eq!(rows[0], "series,spp,seconds,relmse,rmse,flip");
    let keys: Vec<String> = rows[1..]
        .iter()
        .map(|r| r.split(',').take(2).collect::<Vec<_>>().join(","))
        .collect();
    assert_eq!(keys, ["pt-mis,1", "pt-mis,2", "pt-bsdf,1", "pt-bsdf,2"]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("time to reach the other's final relMSE"),
        "{stdout}"
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("summary.txt")).unwrap(),
        stdout
    );
    for f in [
        "converge.svg",
        "converge.png",
        "pt-mis/spp1.exr",
        "pt-bsdf/spp2.exr",
    ] {
        assert!(dir.join(f).is_file(), "{f} missing");
    }
    // BSDF sampling alone is far noisier than MIS on the Cornell box (small light).
    let relmse = |k: usize| rows[k].split(',').nth(3).unwrap().parse::<f64>().unwrap();
    assert!(relmse(4) > 10.0 * relmse(2), "{csv}");
    let o = pt(&[
        "converge",
        "scenes/cornell-box.xml",
        "--reference",
        "references/nonexistent.exr",
        "--out",
        s(&dir.join("no")),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("reference 'references/nonexistent.exr' not found"));
    assert!(!dir.join("no").exists());
}
