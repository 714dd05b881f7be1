//! Renders split into parts (issue 25): `pt render --part K/N` on each share of the sample
//! indices, `pt merge` of the part files.
//!
//! - The merged image equals the render on one machine bit for bit (every channel of the EXR
//!   and of its variance EXR), for N = 1, 3 and 4, parts on 1 or 2 threads, under filter
//!   importance sampling with negative filter weights (Mitchell), Mitsuba's splatting film
//!   (Gaussian) with the `moment` integrator's squared channels, and a structured sampler
//!   (multijitter, whose samples depend on their index within blocks); and for the light
//!   tracer, BDPT, VCM and the photon mapper. A test of equality, not
//!   of statistics: any difference in the reduction (a float sum in another order, a sample
//!   index drawn twice or skipped, a share's stream keyed by its local index) changes bits.
//! - Parts that do not make one render are refused with exit code 2 and no output: a missing,
//!   duplicated or truncated part, parts of another seed or sample count, an unfinished part.
//!   A part stopped by SIGTERM (what Slurm sends) resumes from its file and the merge is still
//!   exact.
//! - `pt slurm` writes the job array, merge job and manifest, and `--status` reads them (the
//!   run on a real Slurm is tests/slurm/run.sh).

use crate::common::*;
use std::path::{Path, PathBuf};

/// Every channel of an EXR as bit patterns, by name.
fn channel_bits(path: &Path) -> Vec<(String, Vec<u32>)> {
    let (_, _, channels) =
        pt_image::read_exr_channels(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    channels
        .into_iter()
        .map(|(n, v)| (n, v.iter().map(|x| x.to_bits()).collect()))
        .collect()
}

fn ok(o: &std::process::Output) {
    assert!(
        o.status.success(),
        "exit {:?}: {}",
        o.status.code(),
        String::from_utf8_lossy(&o.stderr)
    );
}

fn s(p: &Path) -> String {
    p.to_str().expect("utf-8 path").to_string()
}

/// A scene the way Mitsuba users write one, with a structured sampler and a filter with
/// negative lobes.
const MULTIJITTER_SCENE: &str = r#"<scene version="3.0.0">
    <default name="spp" value="12"/>
    <integrator type="path"><integer name="max_depth" value="5"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="35"/>
        <transform name="to_world"><lookat origin="0, 1.2, 4" target="0, 0.3, 0" up="0, 1, 0"/></transform>
        <sampler type="multijitter"><integer name="sample_count" value="$spp"/></sampler>
        <film type="hdrfilm">
            <integer name="width" value="40"/><integer name="height" value="30"/>
            <rfilter type="mitchell"/>
        </film>
    </sensor>
    <bsdf type="roughconductor" id="metal"><string name="material" value="Au"/><float name="alpha" value="0.2"/></bsdf>
    <shape type="sphere"><point name="center" x="0.4" y="0.5" z="0"/><float name="radius" value="0.5"/><ref id="metal"/></shape>
    <shape type="rectangle">
        <transform name="to_world"><rotate x="1" angle="-90"/><scale value="3"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.5, 0.4"/></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><rotate x="1" angle="70"/><translate x="-0.6" y="2" z="0.5"/><scale value="0.6"/></transform>
        <emitter type="area"><rgb name="radiance" value="12, 11, 9"/></emitter>
    </shape>
    <emitter type="constant"><rgb name="radiance" value="0.1"/></emitter>
</scene>
"#;

/// Renders `args` whole, and in `n` parts (part k on 1 + k % 2 threads), merges them, and
/// checks every channel of image and variance is the same bits.
fn check_merge_is_exact(dir: &Path, label: &str, args: &[&str], n: u32) {
    let whole = dir.join(format!("{label}-whole.exr"));
    let merged = dir.join(format!("{label}-{n}-merged.exr"));
    let mut a = vec!["render".to_string()];
    a.extend(args.iter().map(|x| x.to_string()));
    let run = |extra: &[String]| {
        let all: Vec<String> = a.iter().chain(extra).cloned().collect();
        let refs: Vec<&str> = all.iter().map(String::as_str).collect();
        pt(&refs)
    };
    if !whole.exists() {
        ok(&run(&[
            "-o".into(),
            s(&whole),
            "--variance".into(),
            "--threads".into(),
            "2".into(),
            "--quiet".into(),
        ]));
    }
    let parts: Vec<PathBuf> = (1..=n)
        .map(|k| dir.join(format!("{label}-{k}of{n}.ptpart")))
        .collect();
    for (k, p) in parts.iter().enumerate() {
        ok(&run(&[
            "--part".into(),
            format!("{}/{n}", k + 1),
            "-o".into(),
            s(p),
            "--threads".into(),
            (1 + k % 2).to_string(),
            "--quiet".into(),
        ]));
    }
    // Merged in reverse order: the order must not matter.
    let mut m = vec!["merge".to_string()];
    m.extend(parts.iter().rev().map(|p| s(p)));
    m.extend([
        "-o".into(),
        s(&merged),
        "--variance".into(),
        "--quiet".into(),
    ]);
    let refs: Vec<&str> = m.iter().map(String::as_str).collect();
    ok(&pt(&refs));
    for (a, b) in [
        (whole.clone(), merged.clone()),
        (
            dir.join(format!("{label}-whole_var.exr")),
            dir.join(format!("{label}-{n}-merged_var.exr")),
        ),
    ] {
        let (x, y) = (channel_bits(&a), channel_bits(&b));
        assert_eq!(
            x.iter().map(|c| &c.0).collect::<Vec<_>>(),
            y.iter().map(|c| &c.0).collect::<Vec<_>>(),
            "{label}, {n} parts: channels"
        );
        for ((name, p), (_, q)) in x.iter().zip(&y) {
            let differ = p.iter().zip(q).filter(|(u, v)| u != v).count();
            assert_eq!(
                differ,
                0,
                "{label}, {n} parts: channel {name} of {}",
                b.display()
            );
        }
    }
    // The same through the command users have: `pt compare --identical`.
    ok(&pt(&["compare", "--identical", &s(&merged), &s(&whole)]));
}

#[test]
fn merged_parts_equal_the_whole_render() {
    let dir = scratch("cluster_exact");
    let multijitter = dir.join("multijitter.xml");
    std::fs::write(&multijitter, MULTIJITTER_SCENE).unwrap();
    let moment = repo().join("scenes/moment.xml");
    let cases: [(&str, Vec<String>); 3] = [
        (
            "mitchell-importance",
            vec![
                s(&multijitter),
                "--reconstruction".into(),
                "importance".into(),
            ],
        ),
        ("multijitter-splat", vec![s(&multijitter)]),
        (
            "moment-gaussian",
            vec![
                s(&moment),
                "--width".into(),
                "36".into(),
                "--height".into(),
                "28".into(),
                "--spp".into(),
                "10".into(),
            ],
        ),
    ];
    for (label, args) in &cases {
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        for n in [1, 3, 4] {
            check_merge_is_exact(&dir, label, &refs, n);
        }
    }
}

/// The methods from the lights split as exactly: the light tracer's film (splats of light
/// paths, a Gaussian filter), BDPT and VCM (light film plus camera samples, merging radii and
/// wavelengths by iteration) and Jensen's photon mapper (maps per iteration), on the caustic
/// scene.
#[test]
fn light_path_methods_merge_exactly() {
    let dir = scratch("cluster_light");
    let scene = s(&repo().join("scenes/caustic-sphere-light.xml"));
    for (method, spp) in [
        ("ptracer", "12"),
        ("bdpt", "6"),
        ("vcm", "6"),
        ("photonmapper", "3"),
    ] {
        let args = [
            scene.as_str(),
            "--integrator",
            method,
            "--width",
            "32",
            "--height",
            "24",
            "--spp",
            spp,
        ];
        check_merge_is_exact(&dir, method, &args, 3);
    }
}

#[test]
fn parts_that_are_not_one_render_are_refused() {
    let dir = scratch("cluster_refusals");
    let base = ["render", "--width", "24", "--height", "16", "--quiet"];
    let part = |k: &str, extra: &[&str]| {
        let out = dir.join(format!("{}{}.ptpart", k.replace('/', "of"), extra.join("")));
        let mut a: Vec<&str> = base.to_vec();
        let o = s(&out);
        a.extend(["--spp", "8", "--part", k, "-o", &o]);
        a.extend(extra);
        ok(&pt(&a));
        out
    };
    let p1 = part("1/3", &[]);
    let p2 = part("2/3", &[]);
    let p3 = part("3/3", &[]);
    let other_seed = part("3/3", &["--seed", "9"]);
    let truncated = dir.join("truncated.ptpart");
    let bytes = std::fs::read(&p3).unwrap();
    std::fs::write(&truncated, &bytes[..bytes.len() - 100]).unwrap();
    let out = dir.join("never.exr");
    for (parts, says) in [
        (vec![&p1, &p2], "missing part(s): 3/3"),
        (vec![&p1, &p2, &p2, &p3], "given twice"),
        (vec![&p1, &p2, &truncated], "truncated or damaged"),
        (vec![&p1, &p2, &other_seed], "another seed"),
    ] {
        let mut a = vec!["merge".to_string()];
        a.extend(parts.iter().map(|p| s(p)));
        a.extend(["-o".into(), s(&out)]);
        let refs: Vec<&str> = a.iter().map(String::as_str).collect();
        let o = pt(&refs);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{says}: {err}");
        assert!(err.contains(says), "expected '{says}' in: {err}");
        assert!(!out.exists(), "{says}: an output was written");
    }
    // SPPM's iterations depend on the ones before: refused before rendering.
    let o = pt(&[
        "render",
        "--integrator",
        "sppm",
        "--part",
        "1/2",
        "--spp",
        "2",
        "--quiet",
        "-o",
        &s(&dir.join("pt.ptpart")),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--part applies to every"));
    assert!(!dir.join("pt.ptpart").exists());
    let o = pt(&["render", "--part", "4/3", "--quiet"]);
    assert_eq!(o.status.code(), Some(2));
}

/// SIGTERM (Slurm's stop signal) saves the part; the unfinished part is refused by merge; run
/// again, the part resumes from its file, and the merge equals the whole render.
#[cfg(unix)]
#[test]
fn stopped_part_resumes_and_merges_exactly() {
    use std::process::Command;
    use std::time::{Duration, Instant};
    let dir = scratch("cluster_resume");
    let base = [
        "render", "--width", "64", "--height", "64", "--spp", "2000", "--quiet",
    ];
    let p1 = dir.join("p1.ptpart");
    let p2 = dir.join("p2.ptpart");
    let mut a: Vec<String> = base.iter().map(|x| x.to_string()).collect();
    a.extend(["--part", "1/2", "--checkpoint", "0", "-o"].map(String::from));
    a.push(s(&p1));
    let mut child = Command::new(env!("CARGO_BIN_EXE_pt"))
        .args(&a)
        .current_dir(repo())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Wait for a first checkpoint, then stop the part as Slurm would.
    let start = Instant::now();
    while !p1.exists() && start.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(50));
    }
    assert!(p1.exists(), "no checkpoint was written");
    // SAFETY: sends a signal to our own child process.
    #[allow(unsafe_code)]
    unsafe {
        libc::kill(child.id() as i32, libc::SIGTERM);
    }
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130), "a stopped part exits with 130");
    let mut b: Vec<&str> = base.to_vec();
    let (s1, s2) = (s(&p1), s(&p2));
    b.extend(["--part", "2/2", "-o", &s2]);
    ok(&pt(&b));
    let merged = dir.join("merged.exr");
    let o = pt(&["merge", &s1, &s2, "-o", &s(&merged)]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("still running or was stopped"), "{err}");
    assert!(!merged.exists());
    // Resumed (the same command again) to the end, then merged.
    let refs: Vec<&str> = a.iter().map(String::as_str).collect();
    let o = pt(&refs);
    ok(&o);
    ok(&pt(&["merge", &s1, &s2, "-o", &s(&merged), "--quiet"]));
    let whole = dir.join("whole.exr");
    let mut w: Vec<&str> = base.to_vec();
    let ws = s(&whole);
    w.extend(["-o", &ws]);
    ok(&pt(&w));
    assert_eq!(channel_bits(&merged), channel_bits(&whole));
}

#[test]
fn slurm_scripts_and_status() {
    let dir = scratch("cluster_slurm");
    let run = dir.join("run");
    let cornell = s(&repo().join("scenes/cornell-box.xml"));
    let gaussian = s(&repo().join("scenes/film-gaussian.xml"));
    let o = pt(&[
        "slurm",
        &cornell,
        &gaussian,
        "--parts",
        "4",
        "--spp",
        "16",
        "--out",
        &s(&run),
        "--partition",
        "short",
        "--time",
        "10:00",
        "--",
        "--max-depth",
        "4",
    ]);
    ok(&o);
    let script = std::fs::read_to_string(run.join("parts.sbatch")).unwrap();
    assert!(script.contains("#SBATCH --array=0-7\n"), "{script}");
    assert!(script.contains("#SBATCH --requeue"));
    assert!(script.contains("--spp 16") && script.contains("--max-depth 4"));
    let merge = std::fs::read_to_string(run.join("merge.sbatch")).unwrap();
    assert_eq!(merge.matches(" merge ").count(), 2, "{merge}");
    let o = pt(&["slurm", "--status", &s(&run)]);
    ok(&o);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("0 of 8 parts done, 0 of 2 images merged"),
        "{out}"
    );
    // A bad render argument is caught when the scripts are written, not on the cluster.
    let o = pt(&[
        "slurm",
        &cornell,
        "--parts",
        "2",
        "--out",
        &s(&run),
        "--",
        "--max-depht",
        "3",
    ]);
    assert_eq!(o.status.code(), Some(2));
}
