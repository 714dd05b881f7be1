//! BVH traversal throughput (criterion): rays per second for closest-hit (`Accel::intersect`)
//! and occlusion (any-hit, `Accel::occluded`) queries, CWBVH against BVH2, single-threaded,
//! plus the build time of a 1M-triangle BVH.
//!
//! ```sh
//! cargo bench -p pt-render --bench traversal                 # full run (a few minutes)
//! cargo bench -p pt-render --bench traversal -- --quick      # quicker, less precise
//! cargo bench -p pt-render --bench traversal -- incoherent   # a subset, by name filter
//! ```
//!
//! The queries run compiled for x86-64-v3 when the processor has it, as in the renderer;
//! `PT_BENCH_BASELINE=1` runs them compiled for baseline x86-64 instead.
//!
//! Criterion reports `thrpt` in elements/s: one element is one ray, so `Melem/s` = Mrays/s.
//!
//! Scenes: the Cornell box (`scenes/cornell-box.xml`, as the renderer builds it: its 36 triangles
//! are 18 parallelograms) and a displaced cube-sphere of
//! 12 * 296^2 = 1,051,392 triangles generated here. Ray sets (2^16 rays each, generated before
//! timing, with a fixed seed):
//! - `coherent`: one camera ray per pixel through the pixel centre, 256 x 256, in scanline order
//!   (the scene's camera for the Cornell box; a pinhole looking at the sphere for the mesh).
//! - `incoherent`: origins uniform in the scene's bounding box, directions uniform on the sphere,
//!   in random order: the pattern of secondary bounces.
//!
//! - `small/N`: N random triangles and parallelograms in a unit cube with incoherent rays, for
//!   N = 8 .. 128, built as a CWBVH and without a tree (`BvhKind::Flat`): where the crossing
//!   lies decides `accel::FLAT_MAX`.
//!
//! - `PT_BENCH_SCENE=FILE.xml`: a scene file instead (its camera's rays at 256 x 256 and
//!   incoherent rays in its bounds), for a side-by-side with Mitsuba's Embree
//!   (`references/time_mitsuba_rays.py`, the same ray sets' kinds).
//!
//! Both queries use the same rays with `tmax = inf` (occlusion thus measures how fast any-hit
//! traversal finds a first blocker). The traversal runs on the calling thread; the builds use the
//! current rayon pool (obvhs `parallel` feature), measured once with one thread and once with all.
//! Timings include `Accel`'s conversion to the obvhs ray and the primitive intersection closure,
//! i.e. exactly what the integrator pays per ray.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use pt_math::{Mat4, Ray, Vec2, Vec3, Vec3A};
use pt_render::accel::{Accel, BvhKind, BATCH};
use pt_render::camera::Camera;
use pt_render::geometry::Primitive;
use pt_render::{LightSelection, Scene};
use pt_scene::{CameraDesc, FovAxis, Projection, SourceLoc};
use std::hint::black_box;
use std::path::Path;

/// Rays per set.
const RAYS: usize = 1 << 16;
/// Camera image size for coherent rays (RES * RES = RAYS).
const RES: u32 = 256;
/// Cube-sphere subdivision: 6 faces * N^2 quads * 2 = 1,051,392 triangles.
const SPHERE_N: u32 = 296;

const KINDS: [(BvhKind, &str); 2] = [(BvhKind::CwBvh, "cwbvh"), (BvhKind::Bvh2, "bvh2")];
/// Layouts compared on small scenes.
const SMALL_KINDS: [(BvhKind, &str); 2] = [(BvhKind::CwBvh, "cwbvh"), (BvhKind::Flat, "flat")];

/// Small deterministic generator (PCG-style LCG, top 24 bits): benches need no statistics.
struct Rng(u64);

impl Rng {
    fn next_f32(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

fn triangles<'a>(pos: &'a [Vec3], idx: &'a [[u32; 3]]) -> impl Iterator<Item = Primitive> + 'a {
    idx.iter().filter_map(move |t| {
        let [a, b, c] = t.map(|i| Vec3A::from(pos[i as usize]));
        let (e1, e2) = (b - a, c - a);
        (e1.cross(e2).length_squared() > 0.0).then_some(Primitive::Triangle { v0: a, e1, e2 })
    })
}

/// A cube subdivided into `n x n` quads per face, projected onto the unit sphere and displaced
/// radially by a few octaves of sines (a bumpy asteroid), as an indexed mesh.
fn displaced_sphere(n: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut pos = Vec::with_capacity((6 * (n + 1) * (n + 1)) as usize);
    let mut idx = Vec::with_capacity((12 * n * n) as usize);
    // Faces as (normal, u axis, v axis) with u x v = normal, so windings face outwards.
    let faces = [
        (Vec3::X, Vec3::Y, Vec3::Z),
        (-Vec3::X, Vec3::Z, Vec3::Y),
        (Vec3::Y, Vec3::Z, Vec3::X),
        (-Vec3::Y, Vec3::X, Vec3::Z),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (-Vec3::Z, Vec3::Y, Vec3::X),
    ];
    for (normal, u, v) in faces {
        let base = pos.len() as u32;
        for j in 0..=n {
            for i in 0..=n {
                let (s, t) = (
                    2.0 * i as f32 / n as f32 - 1.0,
                    2.0 * j as f32 / n as f32 - 1.0,
                );
                let d = (normal + u * s + v * t).normalize();
                let bump = 0.06 * (7.0 * d.x).sin() * (9.0 * d.y).sin() * (5.0 * d.z).sin()
                    + 0.02 * (31.0 * d.x + 3.0).sin() * (27.0 * d.z).sin()
                    + 0.005 * (97.0 * d.y).sin() * (89.0 * d.x + 1.0).sin();
                pos.push(d * (1.0 + bump));
            }
        }
        for j in 0..n {
            for i in 0..n {
                let a = base + j * (n + 1) + i;
                let (b, c, d) = (a + 1, a + n + 1, a + n + 2);
                idx.push([a, b, d]);
                idx.push([a, d, c]);
            }
        }
    }
    (pos, idx)
}

/// Mitsuba's lookat: columns (left, up, dir, origin).
fn lookat(origin: Vec3, target: Vec3, up: Vec3) -> Mat4 {
    let dir = (target - origin).normalize();
    let left = up.cross(dir).normalize();
    let new_up = dir.cross(left);
    Mat4::from_cols(
        left.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        origin.extend(1.0),
    )
}

/// One ray through each pixel centre of a RES x RES image, scanline order.
fn camera_rays(camera: &Camera) -> Vec<Ray> {
    (0..RES)
        .flat_map(|y| (0..RES).map(move |x| Vec2::new(x as f32 + 0.5, y as f32 + 0.5)))
        .map(|p| {
            let mut r = camera.generate_ray(p, Vec2::splat(0.5));
            r.tmax = f32::INFINITY;
            r
        })
        .collect()
}

/// Origins uniform in the bounds of `prims`, directions uniform on the sphere.
fn random_rays(prims: &[Primitive], seed: u64) -> Vec<Ray> {
    let (lo, hi) = prims
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
            let b = p.aabb();
            (lo.min(Vec3::from(b.min)), hi.max(Vec3::from(b.max)))
        });
    let mut rng = Rng(seed);
    (0..RAYS)
        .map(|_| {
            let o = lo + (hi - lo) * Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            let z = 1.0 - 2.0 * rng.next_f32();
            let phi = std::f32::consts::TAU * rng.next_f32();
            let r = (1.0 - z * z).max(0.0).sqrt();
            Ray::new(o, Vec3::new(r * phi.cos(), r * phi.sin(), z))
        })
        .collect()
}

struct Case {
    scene: String,
    prims: Vec<Primitive>,
    coherent: Vec<Ray>,
    incoherent: Vec<Ray>,
}

fn cornell_case() -> Case {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-box.xml");
    let size = [
        ("width".into(), RES.to_string()),
        ("height".into(), RES.to_string()),
    ];
    // The primitives as the renderer builds them: the box's 36 triangles are 18 parallelograms.
    scene_case(&path, &size, "cornell", 7)
}

/// The scene file `path` (with the `defines`) as the renderer builds it, its camera's rays as
/// the coherent set and incoherent rays drawn from `seed`.
fn scene_case(path: &Path, defines: &[(String, String)], name: &str, seed: u64) -> Case {
    let desc = pt_scene::load_file(path, defines)
        .unwrap_or_else(|e| panic!("cannot load {}: {e}", path.display()));
    let scene = Scene::build(&desc, BvhKind::CwBvh, LightSelection::Power)
        .unwrap_or_else(|e| panic!("cannot build {}: {e:?}", path.display()));
    let prims = scene.primitives().to_vec();
    let camera = Camera::new(&desc.camera, RES, RES);
    Case {
        scene: name.into(),
        coherent: camera_rays(&camera),
        incoherent: random_rays(&prims, seed),
        prims,
    }
}

fn mesh_case() -> Case {
    let (pos, idx) = displaced_sphere(SPHERE_N);
    let prims: Vec<Primitive> = triangles(&pos, &idx).collect();
    let desc = CameraDesc {
        loc: SourceLoc::default(),
        projection: Projection::Perspective {
            fov_deg: 45.0,
            fov_axis: FovAxis::X,
        },
        to_world: lookat(Vec3::new(0.4, 0.8, 3.2), Vec3::ZERO, Vec3::Y),
        near_clip: 0.01,
        far_clip: 100.0,
        principal_point_offset: [0.0; 2],
    };
    let camera = Camera::new(&desc, RES, RES);
    Case {
        scene: "sphere1m".into(),
        coherent: camera_rays(&camera),
        incoherent: random_rays(&prims, 11),
        prims,
    }
}

/// Sum of the closest-hit distances of `rays` (hits only).
#[inline(always)]
fn closest_sum(accel: &Accel, rays: &[Ray]) -> f32 {
    let mut sum = 0.0f32;
    for r in rays {
        if let Some(h) = accel.intersect(black_box(r)) {
            sum += h.t;
        }
    }
    sum
}

/// Number of `rays` that are occluded.
#[inline(always)]
fn occluded_count(accel: &Accel, rays: &[Ray]) -> usize {
    rays.iter().filter(|r| accel.occluded(black_box(r))).count()
}

/// [`closest_sum`] through the batch query the path tracer makes ([`Accel::intersect_batch`]):
/// the rays in groups of [`BATCH`], every lane active.
#[inline(always)]
fn closest_sum_batch(accel: &Accel, rays: &[Ray]) -> f32 {
    let mut sum = 0.0f32;
    let mut out = [None; BATCH];
    for group in rays.chunks_exact(BATCH) {
        let group: &[Ray; BATCH] = group.try_into().expect("BATCH rays");
        accel.intersect_batch(black_box(group), (1 << BATCH) - 1, &mut out);
        sum += out.iter().flatten().map(|h| h.t).sum::<f32>();
    }
    sum
}

/// [`occluded_count`] through [`Accel::occluded_batch`], as [`closest_sum_batch`].
#[inline(always)]
fn occluded_count_batch(accel: &Accel, rays: &[Ray]) -> usize {
    rays.chunks_exact(BATCH)
        .map(|group| {
            let group: &[Ray; BATCH] = group.try_into().expect("BATCH rays");
            accel
                .occluded_batch(black_box(group), (1 << BATCH) - 1)
                .count_ones() as usize
        })
        .sum()
}

/// `work` compiled for x86-64-v3 when the processor has it, as the renderer's tile loop is
/// (`render::render_tile`): the traversal and the SIMD primitive blocks are inlined into it
/// (callers pass a closure marked `#[inline(always)]`).
fn dispatch<R>(work: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    if has_v3() {
        #[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt,movbe")]
        fn v3<R>(work: impl FnOnce() -> R) -> R {
            work()
        }
        // SAFETY: `has_v3` checked every feature `v3` is compiled for.
        return unsafe { v3(work) };
    }
    work()
}

/// Times `query` as `id` in `group`, compiled as [`dispatch`] compiles it (callers pass a
/// closure marked `#[inline(always)]`, so that its body is inlined into the x86-64-v3 variant).
fn bench_query<R>(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    id: BenchmarkId,
    query: impl Fn() -> R + Copy,
) {
    // A closure around `query`, not `query` itself: passed as it is, it ran through an
    // outlined `FnOnce::call_once`, compiled for the baseline.
    #[allow(clippy::redundant_closure)]
    group.bench_function(id, |b| {
        b.iter(|| {
            dispatch(
                #[inline(always)]
                || query(),
            )
        })
    });
}

/// Whether the processor has the x86-64-v3 features (false when `PT_BENCH_BASELINE` is set).
#[cfg(target_arch = "x86_64")]
fn has_v3() -> bool {
    std::env::var_os("PT_BENCH_BASELINE").is_none() && pt_render::has_x86_64_v3()
}

fn bench_traversal(c: &mut Criterion, case: &Case) {
    let kinds: &[(BvhKind, &str)] = if case.prims.len() <= 128 {
        &[KINDS[0], KINDS[1], SMALL_KINDS[1]]
    } else {
        &KINDS
    };
    bench_kinds(c, case, kinds);
}

fn bench_kinds(c: &mut Criterion, case: &Case, kinds: &[(BvhKind, &str)]) {
    for &(kind, kname) in kinds {
        // As `Scene::build` builds it (above 2^18 primitives: a CWBVH per spatial group).
        let accel = Accel::build_compact(case.prims.clone(), kind, |i| case.prims[i]);
        for (rays, rname) in [
            (&case.coherent, "coherent"),
            (&case.incoherent, "incoherent"),
        ] {
            if rays.is_empty() {
                continue;
            }
            let hits = rays.iter().filter(|r| accel.intersect(r).is_some()).count();
            eprintln!(
                "{} ({} prims) {kname} {rname}: {:.1}% of {} rays hit",
                case.scene,
                case.prims.len(),
                100.0 * hits as f64 / rays.len() as f64,
                rays.len()
            );
            let mut g = c.benchmark_group(format!("{}/{rname}", case.scene));
            g.throughput(Throughput::Elements(rays.len() as u64));
            bench_query(
                &mut g,
                BenchmarkId::new("closest", kname),
                #[inline(always)]
                || closest_sum(&accel, rays),
            );
            bench_query(
                &mut g,
                BenchmarkId::new("occluded", kname),
                #[inline(always)]
                || occluded_count(&accel, rays),
            );
            bench_query(
                &mut g,
                BenchmarkId::new("closest-batch", kname),
                #[inline(always)]
                || closest_sum_batch(&accel, rays),
            );
            bench_query(
                &mut g,
                BenchmarkId::new("occluded-batch", kname),
                #[inline(always)]
                || occluded_count_batch(&accel, rays),
            );
            g.finish();
        }
    }
}

/// `n` random triangles and parallelograms (every third) in the unit cube, edges up to 0.5.
fn small_case(n: usize) -> Case {
    let mut rng = Rng(n as u64);
    let mut v = |s: f32| {
        Vec3A::new(
            rng.next_f32() - 0.5,
            rng.next_f32() - 0.5,
            rng.next_f32() - 0.5,
        ) * s
    };
    let prims: Vec<Primitive> = (0..n)
        .map(|k| {
            let (v0, e1, e2) = (v(1.0), v(0.5), v(0.5));
            if k % 3 == 0 {
                Primitive::Parallelogram { v0, e1, e2 }
            } else {
                Primitive::Triangle { v0, e1, e2 }
            }
        })
        .collect();
    Case {
        scene: format!("small/{n}"),
        coherent: Vec::new(),
        incoherent: random_rays(&prims, 5),
        prims,
    }
}

fn traversal(c: &mut Criterion) {
    // `PT_BENCH_SCENE=FILE.xml`: that scene (its primitives, CWBVH only) instead of the two
    // built-in cases, e.g. to set against `references/time_mitsuba_rays.py` on the same file.
    if let Some(path) = std::env::var_os("PT_BENCH_SCENE") {
        let path = Path::new(&path);
        let name = path
            .file_stem()
            .map_or("scene".into(), |s| s.to_string_lossy());
        bench_kinds(c, &scene_case(path, &[], &name, 13), &KINDS[..1]);
        return;
    }
    bench_traversal(c, &cornell_case());
    bench_traversal(c, &mesh_case());
}

/// CWBVH against no tree on small scenes (incoherent rays only).
fn small(c: &mut Criterion) {
    for n in [8, 16, 32, 64, 128] {
        let case = small_case(n);
        bench_kinds(c, &case, &SMALL_KINDS);
    }
}

fn build(c: &mut Criterion) {
    let (pos, idx) = displaced_sphere(SPHERE_N);
    let prims: Vec<Primitive> = triangles(&pos, &idx).collect();
    let mut g = c.benchmark_group(format!("build/sphere1m ({} tris)", prims.len()));
    g.sample_size(10);
    g.throughput(Throughput::Elements(prims.len() as u64));
    let all = rayon::current_num_threads();
    for threads in [1, all] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool");
        for (kind, kname) in KINDS {
            g.bench_function(BenchmarkId::new(kname, format!("{threads}thr")), |b| {
                b.iter_batched(
                    || prims.clone(),
                    |p| pool.install(|| Accel::build_compact(p, kind, |i| prims[i])),
                    criterion::BatchSize::LargeInput,
                )
            });
        }
        if all == 1 {
            break;
        }
    }
    g.finish();
}

criterion_group!(benches, traversal, small, build);
criterion_main!(benches);
