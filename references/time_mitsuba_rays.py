#!/usr/bin/env python3
"""Ray queries per second in Mitsuba 3 (its Embree BVH) on a scene file, to set against pt's
traversal benchmark on the same file (`crates/pt-render/benches/traversal.rs`):

    DRJIT_LIBLLVM_PATH=libLLVM.so.19.1 .venv/bin/python references/time_mitsuba_rays.py \\
        target/bench/scenes/mesh-100k.xml --threads 1
    PT_BENCH_SCENE=target/bench/scenes/mesh-100k.xml \\
        cargo bench -p pt-render --bench traversal -- --quick

The same two kinds of ray set as the Rust benchmark: `coherent`, the scene camera's rays through
the pixel centres of a 256 x 256 image in scanline order, and `incoherent`, origins uniform in
the scene's bounds and directions uniform on the sphere (other random numbers, the same
distributions). Each query runs on the whole set as one kernel (`ray_intersect_preliminary`:
the closest hit without the surface interaction; `ray_test`: any hit), timed after a warm-up
call and with `dr.sync_thread()`, as the render timings are. One element is one ray.
"""

import argparse
import time

import drjit as dr
import mitsuba as mi


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--threads", type=int, default=0, help="Dr.Jit threads (0: all cores)")
    ap.add_argument("--res", type=int, default=256, help="camera rays: res x res")
    ap.add_argument("--rays", type=int, default=1 << 20, help="rays per incoherent set")
    ap.add_argument("--repeat", type=int, default=5, help="timed calls (the best is reported)")
    args = ap.parse_args()
    mi.set_variant(args.variant)
    if args.threads:
        dr.set_thread_count(args.threads)
    scene = mi.load_file(args.scene)

    sets = {"coherent": camera_rays(scene, args.res), "incoherent": random_rays(scene, args.rays)}
    for name, ray in sets.items():
        n = dr.width(ray.o)
        for query, run in (
            ("closest", lambda r: scene.ray_intersect_preliminary(r).t),
            ("occluded", lambda r: scene.ray_test(r)),
        ):
            best = float("inf")
            hits = 0
            for k in range(args.repeat + 1):
                t0 = time.perf_counter()
                out = run(ray)
                dr.eval(out)
                dr.sync_thread()
                dt = time.perf_counter() - t0
                if k > 0:  # the first call traces and compiles the kernel
                    best = min(best, dt)
                if query == "closest":
                    hits = dr.count(dr.isfinite(out))[0]
                else:
                    hits = dr.count(out)[0]
            print(f"{name:10} {query:8} {n:8d} rays  {100 * hits / n:5.1f}% hit  "
                  f"{n / best / 1e6:8.2f} M rays/s")


def camera_rays(scene, res):
    """The sensor's rays through the pixel centres of a res x res image, scanline order."""
    sensor = scene.sensors()[0]
    idx = dr.arange(mi.UInt32, res * res)
    x, y = idx % res, idx // res
    uv = mi.Point2f((mi.Float(x) + 0.5) / res, (mi.Float(y) + 0.5) / res)
    ray, _ = sensor.sample_ray(0.0, 0.5, uv, mi.Point2f(0.5))
    return mi.Ray3f(ray)


def random_rays(scene, n):
    """Origins uniform in the scene's bounds, directions uniform on the sphere."""
    sampler = mi.PCG32(size=n, initstate=13)
    box = scene.bbox()
    u = mi.Vector3f(sampler.next_float32(), sampler.next_float32(), sampler.next_float32())
    o = mi.Point3f(box.min + (box.max - box.min) * u)
    d = mi.warp.square_to_uniform_sphere(
        mi.Point2f(sampler.next_float32(), sampler.next_float32()))
    return mi.Ray3f(o, d)


if __name__ == "__main__":
    main()
