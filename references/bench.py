#!/usr/bin/env python3
"""The benchmark suite: pt against Mitsuba 3.9.1 on scenes made like public ones, in one
sitting, by time to equal noise (issue 22).

    .venv/bin/python references/bench.py                     # every scene, prints the table
    .venv/bin/python references/bench.py --scenes staircase,mesh-1m
    .venv/bin/python references/bench.py --write             # also replaces the table in
                                                             # references/performance.md
    .venv/bin/python references/bench.py --scaling [--write]  # thread scaling instead: 1 and
                                                             # 2 threads, both renderers

Needs a release build (`cargo build --release`) and the virtual environment of
references/README.md (Mitsuba 3.9.1 with the LLVM backend: DRJIT_LIBLLVM_PATH is set to
libLLVM.so.19.1 unless already set). Generated scenes (big meshes, instances, many lights) are
written first by references/make_bench_scenes.py into target/bench/scenes (once; --regenerate
writes them again); the others are the repository's own scenes.

Figure of merit (no reference image needed): each renderer renders a scene twice at the same
spp with two seeds, a and b; noise = mean over pixels and channels of (a - b)^2 / (m^2 + 0.01)
/ 2, m = (a + b) / 2 (the relative variance of one render; 0.01 keeps dark pixels from
dominating); work-normalised error = noise x seconds; the score is pt's over Mitsuba's (below 1:
pt reaches the same noise sooner). pt is timed as the whole process (load, build, render,
write), Mitsuba as the `mi.render` call after a warm-up render of the same scene (kernels
compiled, `dr.sync_thread()` after each), which is generous to Mitsuba. Also reported: samples
per second, scene load + build time (pt: whole process minus its render; Mitsuba: `load_file`),
and peak resident memory (pt: the process; Mitsuba: its process after loading and rendering,
Python and the Dr.Jit runtime included). RGB scenes run against llvm_ad_rgb, spectral ones
(detected as references/make_references.py detects them) against llvm_ad_spectral.

Thread scaling (--scaling): each scene at a quarter of its spp (at least 4), rendered by pt with
`--threads 1` and `--threads 2` (pt's own render time, load excluded) and by Mitsuba with
`dr.set_thread_count(1)` and `(2)` (its render after a warm-up; a Mitsuba run that does not
finish in 3 minutes is reported as such: at one thread, scenes with an environment map never
finished loading); the table gives
samples per second at each count and the speed-up 2 threads / 1 thread of each renderer, and
`--write` puts it between the scaling markers of references/performance.md.

Output: the table (markdown) on stdout, and every figure in target/bench/results.json
(target/bench/scaling.json with --scaling).
"""

import argparse
import datetime
import json
import math
import os
import platform
import re
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
BENCH = REPO / "target" / "bench"
GENERATED = BENCH / "scenes"

# name, scene file, spp, scene parameters (-D), what it exercises. Sample counts give each pt
# render 2-10 s on the project's 2-core machine, so that process start-up does not dominate.
SUITE = [
    ("cornell-box", "scenes/cornell-box.xml", 256, {}, "the baseline: Lambert, one rectangle light, box filter"),
    ("staircase", "scenes/staircase.xml", 64, {"width": "320", "height": "240"},
     "Bitterli kind: 307 OBJ shapes, textured roughplastic, bumpmap, conductors, gaussian, max_depth 65"),
    ("veach-mis", "scenes/atlas/veach-mis.xml", 2048, {}, "sphere lights of four sizes, rough plates"),
    ("conductors", "scenes/conductors.xml", 1024, {}, "rough conductors, environment map"),
    ("dielectrics", "scenes/dielectrics.xml", 1024, {}, "smooth, rough and thin glass"),
    ("emissive-mesh", "scenes/emissive-mesh.xml", 1024, {}, "an OBJ mesh as area light"),
    ("texture-bitmap", "scenes/texture-bitmap.xml", 1024, {}, "bitmap textures on several parameters"),
    ("film-tent", "scenes/film-tent.xml", 4096, {}, "tent filter"),
    ("cornell-spectral", "scenes/cornell-spectral.xml", 256, {}, "spectral mode (measured spectra)"),
    ("mesh-100k", "generated:mesh-100k.xml", 256, {}, "100k-triangle OBJ, rough plastic, gaussian"),
    ("mesh-1m", "generated:mesh-1m.xml", 128, {}, "1M-triangle PLY, rough conductor, envmap, tent"),
    ("mesh-5m", "generated:mesh-5m.xml", 128, {}, "5M-triangle serialized mesh, sphere light, box"),
    ("instances", "generated:instances.xml", 16, {}, "1,000 instances of 100k-triangle groups"),
    ("many-lights", "generated:many-lights.xml", 256, {}, "144 sphere lights"),
    ("ptracer-sphere", "scenes/caustic-sphere-light.xml", 256, {},
     "ptracer: light paths through a glass ball, small sphere light, gaussian"),
    ("ptracer-point", "scenes/caustic-point-light.xml", 256, {},
     "ptracer: a point light's caustic through a glass ball, gaussian"),
    ("fog-spot", "scenes/fog-spot.xml", 256, {},
     "volpath: chromatic hg fog behind null walls, spot light shafts, sky"),
    ("smoke-grid", "scenes/smoke-grid.xml", 256, {},
     "volpath: 40^3 gridvolume smoke, delta and ratio tracking, sun and sky"),
    ("dye-plume", "scenes/dye-plume.xml", 512, {},
     "volpath: RGB extinction and albedo gridvolumes, hg, area light"),
    ("sunsky", "scenes/sunsky.xml", 512, {}, "Hosek-Wilkie sun and sky, gold sphere, checkerboard ground"),
    ("sunsky-spectral", "scenes/sunsky-spectral.xml", 256, {},
     "spectral sun and sky, limb-darkened sun, measured albedo"),
    ("hair-fibres", "scenes/hair-fibres.xml", 256, {}, "hair BSDF on 24 cylinder fibres, area light"),
]

SEEDS = (1, 2)


def scene_path(spec):
    if spec.startswith("generated:"):
        return GENERATED / spec.split(":", 1)[1]
    return REPO / spec


def colour_mode(path):
    sys.path.insert(0, str(REPO / "references"))
    from make_references import colour_mode as mode  # noqa: E402

    return mode(path.read_text())[0]


def noise(a, b):
    """Relative variance of one render from two renders with different seeds."""
    import numpy as np

    m = (a + b) / 2
    return float(np.mean((a - b) ** 2 / (m * m + 0.01)) / 2)


def read_rgb(path):
    import mitsuba as mi
    import numpy as np

    if not mi.variant():
        mi.set_variant("scalar_rgb")
    return np.array(mi.Bitmap(str(path)), dtype=np.float64)[..., :3]


def run_pt(pt, scene, spp, params, seed, out, threads=None):
    """Whole-process wall time, render time, samples/s and peak memory of one pt render."""
    cmd = ["/usr/bin/time", "-f", "TIME %e %M", str(pt), "render", str(scene), "-o", str(out),
           "--spp", str(spp), "--seed", str(seed)]
    if threads:
        cmd += ["--threads", str(threads)]
    for k, v in params.items():
        cmd += ["-D", f"{k}={v}"]
    t = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t
    if r.returncode != 0:
        raise RuntimeError(f"pt failed on {scene}: {r.stderr.strip()[-2000:]}")
    text = r.stdout + r.stderr
    m = re.search(r"at (\d+) spp in ([\d.]+) s \(([\d.]+) M samples/s", text)
    peak = re.search(r"TIME [\d.]+ (\d+)", text)
    return {
        "wall_s": wall,
        "render_s": float(m.group(2)),
        "msamples_per_s": float(m.group(3)),
        "peak_mb": int(peak.group(1)) / 1024,
    }


def mitsuba_worker(args):
    """In its own process: load, warm up, render with each seed; print the figures as JSON."""
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", "libLLVM.so.19.1")
    import resource

    import drjit as dr
    import mitsuba as mi

    if args.worker_threads:
        # Before the variant is set: set afterwards, the first render never finished.
        dr.set_thread_count(args.worker_threads)
    mi.set_variant(args.variant)
    params = json.loads(args.params)
    t = time.perf_counter()
    scene = mi.load_file(args.scene, **params)
    dr.sync_thread()
    load = time.perf_counter() - t
    t = time.perf_counter()
    img = mi.render(scene, spp=args.spp, seed=0)
    dr.eval(img)
    dr.sync_thread()
    warm = time.perf_counter() - t
    times = []
    # No outputs: one timed render, nothing written (the thread-scaling runs).
    for seed, out in zip(SEEDS, args.outputs or [None]):
        t = time.perf_counter()
        img = mi.render(scene, spp=args.spp, seed=seed)
        dr.eval(img)
        dr.sync_thread()
        times.append(time.perf_counter() - t)
        if out:
            mi.Bitmap(img).write(out)
    size = scene.sensors()[0].film().crop_size()
    print(json.dumps({
        "load_s": load,
        "first_render_s": warm,
        "render_s": times,
        "pixels": int(size[0]) * int(size[1]),
        "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    }))


def run_mitsuba(scene, variant, spp, params, outs, threads=None):
    cmd = [sys.executable, __file__, "--mitsuba-worker", "--scene", str(scene), "--variant",
           variant, "--spp", str(spp), "--params", json.dumps(params), "--outputs",
           *map(str, outs)]
    if threads:
        cmd += ["--worker-threads", str(threads)]
    try:
        # With one Dr.Jit thread some scenes never finish loading (those with an environment
        # map, 2026-12-05; taskset to one processor and serial loading hung too): those runs
        # are reported as not finished.
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=180 if threads else None)
    except subprocess.TimeoutExpired:
        return None
    if r.returncode != 0:
        raise RuntimeError(f"Mitsuba failed on {scene}: {r.stderr.strip()[-2000:]}")
    return json.loads(r.stdout.strip().splitlines()[-1])


def geomean(xs):
    xs = [x for x in xs if x > 0 and math.isfinite(x)]
    return math.exp(sum(map(math.log, xs)) / len(xs)) if xs else float("nan")


def table(rows, meta):
    out = [
        f"Machine: {meta['machine']}, {meta['cpus']} cores; pt {meta['pt_commit']}; Mitsuba "
        f"3.9.1; {meta['date']}. Command: `.venv/bin/python references/bench.py`.",
        "",
        "| scene (what it exercises), spp | variant | pt s (whole) | Mitsuba s (render) | pt noise | Mitsuba noise "
        "| **time to equal noise, pt / Mitsuba** | M samples/s pt / Mitsuba | load + build s pt / Mitsuba "
        "| peak MB pt / Mitsuba |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        out.append(
            f"| `{r['name']}` ({r['what']}), {r['spp']} | {r['variant']} | {r['pt_s']:.2f} | "
            f"{r['mi_s']:.2f} | {r['pt_noise']:.3g} | {r['mi_noise']:.3g} | **{r['ratio']:.2f}** | "
            f"{r['pt_msps']:.2f} / {r['mi_msps']:.2f} | {r['pt_startup_s']:.2f} / {r['mi_load_s']:.2f} | "
            f"{r['pt_peak_mb']:.0f} / {r['mi_peak_mb']:.0f} |")
    ratios = [r["ratio"] for r in rows]
    out += ["", f"Geometric mean of the time-to-equal-noise ratio: **{geomean(ratios):.2f}** over "
            f"{len(ratios)} scenes (worst {max(ratios):.2f}, best {min(ratios):.2f})."]
    return "\n".join(out)


def machine_meta():
    """Date, processor, core count and pt's commit, for a table's first line."""
    commit = subprocess.run(["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    meta = {
        "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "machine": platform.processor() or platform.machine(),
        "cpus": os.cpu_count(),
        "pt_commit": commit,
    }
    try:
        model = next(l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo")
                     if l.startswith("model name"))
        meta["machine"] = model
    except (OSError, StopIteration):
        pass
    return meta


def write_section(text, name):
    """Replaces the text between `<!-- NAME:begin -->` and `<!-- NAME:end -->` in
    references/performance.md (written atomically)."""
    perf = REPO / "references" / "performance.md"
    doc = perf.read_text()
    begin, end = f"<!-- {name}:begin -->", f"<!-- {name}:end -->"
    if begin not in doc:
        sys.exit(f"{perf} has no {begin} ... {end} section to replace")
    head, rest = doc.split(begin, 1)
    _, tail = rest.split(end, 1)
    tmp = perf.with_suffix(".tmp")
    tmp.write_text(head + begin + "\n" + text + "\n" + end + tail)
    os.replace(tmp, perf)


def scaling(args, chosen, images):
    """The thread-scaling table (see the module documentation)."""
    rows = []
    for name, spec, spp, params, what in chosen:
        scene = scene_path(spec)
        variant = f"llvm_ad_{colour_mode(scene)}"
        spp = max(4, spp // 4)
        row = {"name": name, "spp": spp, "variant": variant}
        for threads in (1, 2):
            print(f"{name}: pt, {threads} thread(s) ...", file=sys.stderr)
            r = run_pt(args.pt, scene, spp, params, SEEDS[0], images / f"{name}-scaling.exr", threads)
            row[f"pt_{threads}"] = r["msamples_per_s"]
            print(f"{name}: Mitsuba {variant}, {threads} thread(s) ...", file=sys.stderr)
            mi = run_mitsuba(scene, variant, spp, params, [], threads)
            row[f"mi_{threads}"] = mi and mi["pixels"] * spp / mi["render_s"][0] / 1e6
        rows.append(row)
    meta = machine_meta()
    out = [f"Machine: {meta['machine']}, {meta['cpus']} cores; pt {meta['pt_commit']}; Mitsuba "
           f"3.9.1; {meta['date']}. Command: `.venv/bin/python references/bench.py --scaling`.", "",
           "| scene, spp | variant | pt M samples/s, 1 / 2 threads | pt speed-up | Mitsuba M "
           "samples/s, 1 / 2 threads | Mitsuba speed-up | pt / Mitsuba samples/s, 1 thread |",
           "|---|---|---|---|---|---|---|"]
    fmt = lambda v: "did not finish" if v is None else f"{v:.2f}"
    ratio = lambda a, b: None if a is None or b is None else a / b
    for r in rows:
        out.append(f"| `{r['name']}`, {r['spp']} | {r['variant']} | {r['pt_1']:.2f} / {r['pt_2']:.2f} "
                   f"| {r['pt_2'] / r['pt_1']:.2f} | {fmt(r['mi_1'])} / {fmt(r['mi_2'])} | "
                   f"{fmt(ratio(r['mi_2'], r['mi_1']))} | {fmt(ratio(r['pt_1'], r['mi_1']))} |")
    mi_up = [x for x in (ratio(r["mi_2"], r["mi_1"]) for r in rows) if x is not None]
    out += ["", f"Geometric mean speed-up from 1 to 2 threads: pt **{geomean([r['pt_2'] / r['pt_1'] for r in rows]):.2f}** "
            f"over {len(rows)} scenes, Mitsuba **{geomean(mi_up):.2f}** over the {len(mi_up)} it finished."]
    text = "\n".join(out)
    print(text)
    (BENCH / "scaling.json").write_text(json.dumps({"meta": meta, "rows": rows}, indent=1))
    if args.write:
        write_section(text, "scaling")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", help="comma-separated names (default: all)")
    ap.add_argument("--pt", default=str(REPO / "target" / "release" / "pt"))
    ap.add_argument("--regenerate", action="store_true", help="write the generated scenes again")
    ap.add_argument("--write", action="store_true",
                    help="replace the suite's table in references/performance.md")
    ap.add_argument("--scaling", action="store_true",
                    help="measure thread scaling (1 and 2 threads) instead of time to equal noise")
    ap.add_argument("--mitsuba-worker", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--worker-threads", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--scene", help=argparse.SUPPRESS)
    ap.add_argument("--variant", help=argparse.SUPPRESS)
    ap.add_argument("--spp", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--params", help=argparse.SUPPRESS)
    ap.add_argument("--outputs", nargs="*", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.mitsuba_worker:
        return mitsuba_worker(args)

    chosen = SUITE
    if args.scenes:
        names = args.scenes.split(",")
        unknown = set(names) - {s[0] for s in SUITE}
        if unknown:
            sys.exit(f"unknown scene(s): {', '.join(sorted(unknown))}; the suite has "
                     f"{', '.join(s[0] for s in SUITE)}")
        chosen = [s for s in SUITE if s[0] in names]
    if not Path(args.pt).exists():
        sys.exit(f"{args.pt} not found: run `cargo build --release` first")
    if any(s[1].startswith("generated:") for s in chosen) and (
            args.regenerate or not (GENERATED / "many-lights.xml").exists()):
        print("writing the generated scenes ...", file=sys.stderr)
        subprocess.run([sys.executable, str(REPO / "references" / "make_bench_scenes.py"),
                        str(GENERATED)], check=True)
    images = BENCH / "images"
    images.mkdir(parents=True, exist_ok=True)
    if args.scaling:
        return scaling(args, chosen, images)
    rows = []
    for name, spec, spp, params, what in chosen:
        scene = scene_path(spec)
        mode = colour_mode(scene)
        variant = f"llvm_ad_{mode}"
        print(f"{name}: pt ...", file=sys.stderr)
        pt_out = [images / f"{name}-pt-{s}.exr" for s in SEEDS]
        pt_runs = [run_pt(args.pt, scene, spp, params, s, o) for s, o in zip(SEEDS, pt_out)]
        print(f"{name}: Mitsuba {variant} ...", file=sys.stderr)
        mi_out = [images / f"{name}-mitsuba-{s}.exr" for s in SEEDS]
        mi = run_mitsuba(scene, variant, spp, params, mi_out)
        pt_noise = noise(*map(read_rgb, pt_out))
        mi_noise = noise(*map(read_rgb, mi_out))
        pt_s = sum(r["wall_s"] for r in pt_runs) / len(pt_runs)
        mi_s = sum(mi["render_s"]) / len(mi["render_s"])
        row = {
            "name": name, "what": what, "spp": spp, "variant": variant,
            "pt_s": pt_s, "mi_s": mi_s, "pt_noise": pt_noise, "mi_noise": mi_noise,
            "ratio": (pt_noise * pt_s) / (mi_noise * mi_s),
            "pt_msps": sum(r["msamples_per_s"] for r in pt_runs) / len(pt_runs),
            "mi_msps": mi["pixels"] * spp / mi_s / 1e6,
            "pt_startup_s": sum(r["wall_s"] - r["render_s"] for r in pt_runs) / len(pt_runs),
            "mi_load_s": mi["load_s"], "mi_first_render_s": mi["first_render_s"],
            "pt_peak_mb": max(r["peak_mb"] for r in pt_runs), "mi_peak_mb": mi["peak_mb"],
            "pt_runs": pt_runs, "mitsuba": mi,
        }
        rows.append(row)
        print(f"{name}: ratio {row['ratio']:.2f} (pt {pt_s:.2f} s noise {pt_noise:.3g}; Mitsuba "
              f"{mi_s:.2f} s noise {mi_noise:.3g})", file=sys.stderr)
    meta = machine_meta()
    text = table(rows, meta)
    print(text)
    (BENCH / "results.json").write_text(json.dumps({"meta": meta, "rows": rows}, indent=1))
    if args.write:
        write_section(text, "bench")


if __name__ == "__main__":
    main()
