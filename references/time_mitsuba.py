#!/usr/bin/env python3
"""Time Mitsuba 3 on a scene, as a yardstick for the Rust renderer.

Usage (from the repository root, with the virtual environment of references/README.md):

    .venv/bin/python references/time_mitsuba.py
    .venv/bin/python references/time_mitsuba.py scenes/cornell-box.xml --spp 64 256 \\
        --max-depth 8 --variants scalar_rgb llvm_ad_rgb

For every variant and spp value it reports the wall time of `mi.render` (including the final
evaluation of the image), and samples per second = width * height * spp / time.  For llvm_ad_*
variants two calls are timed: the first includes tracing and JIT compilation of the kernel (run
with an empty Dr.Jit kernel cache unless --warm-cache is given, so it is a true cold start), the
second is warm (same kernel, different seed).  For scalar variants the two calls are equivalent;
both are reported.  Each variant runs in its own Python process.  Output: a table, then a JSON
document, both on stdout.

Scene parameters: `--max-depth` is passed as the scene parameter $max_depth (only if the scene
declares it with <default name="max_depth" .../>); spp is passed to mi.render.  The machine's core
count is reported: Mitsuba uses all cores (scalar: its thread pool; llvm: Dr.Jit's thread pool).
"""

import argparse
import json
import os
import platform
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
DEFAULT_SCENE = REPO / "scenes" / "cornell-box.xml"


def worker(scene, variant, spp_list, max_depth, seed):
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", "libLLVM.so.19.1")
    import drjit as dr
    import mitsuba as mi

    t = time.perf_counter()
    mi.set_variant(variant)
    params = {}
    text = Path(scene).read_text()
    if max_depth is not None and re.search(r"<default\s+name\s*=\s*[\"']max_depth[\"']", text):
        params["max_depth"] = max_depth
    sc = mi.load_file(str(scene), **params)
    t_load = time.perf_counter() - t
    w, h = (int(x) for x in sc.sensors()[0].film().size())
    md = re.search(r"max_depth\s*=\s*(-?\d+)", str(sc.integrator()))
    rows = []
    for spp in spp_list:
        times = []
        for call in range(2):
            t = time.perf_counter()
            img = mi.render(sc, spp=spp, seed=seed + call)
            dr.eval(img)
            dr.sync_thread()
            times.append(time.perf_counter() - t)
        n = w * h * spp
        rows.append({
            "variant": variant, "spp": spp, "width": w, "height": h,
            "max_depth": int(md.group(1)) if md else None,
            "first_s": round(times[0], 4), "second_s": round(times[1], 4),
            "first_samples_per_s": round(n / times[0]), "second_samples_per_s": round(n / times[1]),
        })
    return {"variant": variant, "load_s": round(t_load, 4), "rows": rows,
            "mitsuba_version": mi.__version__, "drjit_version": dr.__version__,
            "drjit_libllvm_path": os.environ.get("DRJIT_LIBLLVM_PATH")
            if variant.startswith("llvm") else None}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene", nargs="?", default=str(DEFAULT_SCENE))
    ap.add_argument("--spp", type=int, nargs="+", default=[64])
    ap.add_argument("--max-depth", type=int, default=8)
    ap.add_argument("--variants", nargs="+", default=["scalar_rgb", "llvm_ad_rgb"])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--warm-cache", action="store_true",
                    help="keep the Dr.Jit on-disk kernel cache (first llvm call may skip compiling)")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    scene = Path(args.scene)
    if not scene.is_file():
        scene = REPO / "scenes" / (args.scene if args.scene.endswith(".xml") else args.scene + ".xml")

    if args.worker:
        print(json.dumps(worker(scene, args.variants[0], args.spp, args.max_depth, args.seed)))
        return 0

    results = []
    for v in args.variants:
        env = os.environ.copy()
        env.setdefault("DRJIT_LIBLLVM_PATH", "libLLVM.so.19.1")
        with tempfile.TemporaryDirectory(prefix="drjit-cold-") as home:
            cold = v.startswith("llvm") and not args.warm_cache
            if cold:
                env["HOME"] = home  # Dr.Jit keeps its kernel cache in $HOME/.drjit
            cmd = [sys.executable, __file__, str(scene), "--worker", "--variants", v,
                   "--max-depth", str(args.max_depth), "--seed", str(args.seed), "--spp",
                   *map(str, args.spp)]
            t = time.perf_counter()
            r = subprocess.run(cmd, capture_output=True, text=True, env=env)
            wall = time.perf_counter() - t
        if r.returncode != 0:
            print(f"{v}: failed\n{r.stderr}", file=sys.stderr)
            continue
        res = json.loads(r.stdout.strip().splitlines()[-1])
        res["process_wall_s"] = round(wall, 2)
        res["cold_kernel_cache"] = cold
        results.append(res)

    hdr = (f"{'variant':<14} {'spp':>6} {'size':>9} {'depth':>5} {'1st call s':>11} "
           f"{'2nd call s':>11} {'1st Msamples/s':>15} {'2nd Msamples/s':>15}")
    print(f"scene {scene.name}, {os.cpu_count()} cores, {platform.processor() or platform.machine()}")
    print(hdr)
    print("-" * len(hdr))
    for res in results:
        for row in res["rows"]:
            print(f"{row['variant']:<14} {row['spp']:>6} {row['width']:>4}x{row['height']:<4} "
                  f"{str(row['max_depth']):>5} {row['first_s']:>11.3f} {row['second_s']:>11.3f} "
                  f"{row['first_samples_per_s'] / 1e6:>15.3f} {row['second_samples_per_s'] / 1e6:>15.3f}")
    print("(llvm 1st call includes tracing + JIT compilation"
          + ("" if args.warm_cache else " with an empty kernel cache") + ")")
    print()
    print(json.dumps({"scene": str(scene.relative_to(REPO)) if scene.is_relative_to(REPO)
                      else str(scene), "cpu_count": os.cpu_count(), "results": results},
                     indent=2))
    return 0 if results else 1


if __name__ == "__main__":
    sys.exit(main())
