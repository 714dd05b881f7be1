//! Cornell-box study: relMSE against the Mitsuba reference vs patch size, with timings and memory.
//! `cargo run --release -p pt-radiosity --example study -- [rays] [display] [sizes...]`
use pt_radiosity::*;
use std::path::Path;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let rays: u32 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1024);
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut desc = pt_scene::load_file(&root.join("scenes/cornell-box.xml"), &[]).unwrap();
    let (reference, _) = pt_image::read_exr(&root.join("references/cornell-box.exr")).unwrap();
    let sizes: Vec<f32> = if args.len() > 3 {
        args[3..].iter().map(|s| s.parse().unwrap()).collect()
    } else {
        vec![0.4, 0.2, 0.1, 0.05]
    };
    let display = match args.get(2).map(String::as_str) {
        Some("constant") => Display::Constant,
        Some("gather") => Display::FinalGather,
        _ => Display::Smoothed,
    };
    desc.film.width = 256;
    desc.film.height = 256;
    for h in sizes {
        let params = RadiosityParams {
            patch_size: Some(h),
            rays_per_patch: rays,
            ..Default::default()
        };
        let sim = simulate(&desc, &params, &|_, _| {}).unwrap();
        let t = std::time::Instant::now();
        let spp = if display == Display::FinalGather {
            64
        } else {
            4
        };
        let img = sim.render_image(&desc, display, spp, 0, &|_| {});
        let dt = t.elapsed();
        let m = pt_image::metrics::compare(
            &pt_image::Image {
                width: img.width,
                height: img.height,
                data: img.mean,
            },
            &reference,
        )
        .unwrap();
        let s = &sim.stats;
        println!("h {h:6.3} patches {:6} nnz {:9} ({:.1}/row) ff {:6.2}s (recip {:5.2}s) bal {:3} solve {:6.3}s it {:3} res {:.1e} disp {:.2}s mem {:6.1} MB relMSE {:.5} ratio {:.3?}",
            s.patches, s.nnz, s.nnz as f64 / s.patches as f64, s.form_factor_time.as_secs_f64(), s.reciprocity_time.as_secs_f64(), s.balance_iterations, s.solve_time.as_secs_f64(), s.iterations,
            s.residual.iter().cloned().fold(0.0, f32::max), dt.as_secs_f64(), s.memory_bytes as f64 / 1e6, m.relmse_all, m.mean_ratio);
    }
}
