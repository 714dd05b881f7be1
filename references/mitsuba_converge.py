#!/usr/bin/env python3
"""Render a scene with Mitsuba 3 at several sample counts, timing each render: the Mitsuba half
of `pt converge --mitsuba` (which runs this script and computes the errors itself).

Usage (from the repository root, with the virtual environment of references/README.md):

    .venv/bin/python references/mitsuba_converge.py scenes/cornell-box.xml --spp 4 16 64 256 \\
        --out /tmp/converge-cb/mitsuba [--variant llvm_ad_rgb] [--seed 1000] [--threads 2] \\
        [--max-depth 8] [-D name=value ...]

For each sample count N it writes OUT/spp<N>.exr (float32 linear RGB, written atomically) and
prints one line on stdout:

    point <N> <seconds>

where seconds is the wall time of `mi.render(scene, spp=N, seed=...)` followed by `dr.eval` and
`dr.sync_thread` (the image is complete), and nothing else: no scene loading, no conversion to
numpy, no file writing.  Before the timed renders, one untimed warm-up render at the smallest N
(different seed) traces and JIT-compiles the llvm kernel; Dr.Jit reuses that kernel for every
sample count and seed, so the timed renders are warm.  Other stdout lines are `info <key> <value>`
(variant, Mitsuba version, scene load time, warm-up time, thread count).  Progress goes to stderr.

Seeds: render i (0-based, in the order given) uses --seed + i, the warm-up --seed + 1000000;
the references were made with seeds 0..63, so the default --seed 1000 keeps the renders
independent of the reference.

Scene parameters: -D name=value is passed to mi.load_file (the scene's <default> values);
--max-depth D sets the scene parameter $max_depth, so the scene must declare
<default name="max_depth" .../>.  --threads sets Dr.Jit's thread count (all cores by default).
Plugins for project-only models are registered exactly as references/make_references.py does.

Exit codes: 0 success; 2 bad input (Mitsuba or numpy cannot be imported, unusable variant, scene
that does not load, bad argument); 1 a render failed.
"""

import argparse
import os
import re
import sys
import time
from pathlib import Path

# Before Dr.Jit initialises its LLVM backend (older system LLVMs load but fail to compile).
os.environ.setdefault("DRJIT_LIBLLVM_PATH", "libLLVM.so.19.1")

REF_DIR = Path(__file__).resolve().parent
VARIANTS = ("llvm_ad_rgb", "scalar_rgb", "llvm_ad_spectral", "scalar_spectral")


def log(*a):
    print(*a, file=sys.stderr, flush=True)


def out(*a):
    print(*a, flush=True)


def fail(msg, code=2):
    log(f"error: {msg}")
    sys.exit(code)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene", help="Mitsuba 3 XML scene file")
    ap.add_argument("--spp", type=int, nargs="+", required=True, help="sample counts")
    ap.add_argument("--out", required=True, help="folder for the spp<N>.exr images")
    ap.add_argument("--variant", choices=VARIANTS, default="llvm_ad_rgb")
    ap.add_argument("--seed", type=int, default=1000)
    ap.add_argument("--threads", type=int, help="Dr.Jit worker threads (default: all cores)")
    ap.add_argument("--max-depth", type=int, help="sets the scene parameter $max_depth")
    ap.add_argument("-D", dest="defines", action="append", default=[], metavar="NAME=VALUE",
                    help="scene parameter, as Mitsuba's -D (repeatable)")
    args = ap.parse_args()

    if any(n < 1 for n in args.spp):
        fail("--spp values must be >= 1")
    if args.threads is not None and args.threads < 1:
        fail("--threads must be >= 1")
    scene_path = Path(args.scene)
    if not scene_path.is_file():
        fail(f"scene '{scene_path}' not found")
    params = {}
    for d in args.defines:
        k, sep, v = d.partition("=")
        if not sep or not k.strip():
            fail(f"-D expects NAME=VALUE, got '{d}'")
        params[k.strip()] = v
    if args.max_depth is not None:
        text = re.sub(r"<!--.*?-->", "", scene_path.read_text(), flags=re.S)
        if not re.search(r"<default\s+name\s*=\s*[\"']max_depth[\"']", text):
            fail(f"--max-depth needs the scene to declare <default name=\"max_depth\" .../>; "
                 f"'{scene_path}' does not")
        params["max_depth"] = str(args.max_depth)

    try:
        import numpy as np
        import drjit as dr
        import mitsuba  # noqa: F401
    except ImportError as e:
        fail(f"cannot import Mitsuba 3 ({e}) with {sys.executable}; install it as "
             f"references/README.md says (python3 -m venv .venv && .venv/bin/pip install "
             f"mitsuba==3.9.1 numpy)")
    # Shared with the reference pipeline: plugin registration, EXR writing, llvm probe.
    sys.path.insert(0, str(REF_DIR))
    from make_references import EXPECTED_MITSUBA, Mitsuba, base_rgb, llvm_works, write_exr

    if args.variant.startswith("llvm") and not llvm_works(args.variant.split("_")[-1]):
        fail(f"Mitsuba variant {args.variant} does not work here (DRJIT_LIBLLVM_PATH="
             f"{os.environ.get('DRJIT_LIBLLVM_PATH')}; see references/README.md); try "
             f"--mitsuba-variant scalar_rgb")
    msb = Mitsuba()
    mi = msb.mi
    try:
        msb.set_variant(args.variant)
    except Exception as e:  # noqa: BLE001
        fail(f"Mitsuba variant {args.variant} unavailable: {e}")
    if args.threads is not None:
        dr.set_thread_count(args.threads)
    out("info variant", args.variant)
    out("info mitsuba_version", mi.__version__)
    out("info threads", dr.thread_count())
    if mi.__version__ != EXPECTED_MITSUBA:
        log(f"warning: Mitsuba {mi.__version__}; the references are made with {EXPECTED_MITSUBA}")

    t = time.perf_counter()
    try:
        scene = mi.load_file(str(scene_path), **params)
    except Exception as e:  # noqa: BLE001
        fail(f"Mitsuba cannot load '{scene_path}': {e}")
    out("info load_s", f"{time.perf_counter() - t:.6f}")

    out_dir = Path(args.out)
    out_dir.mkdir(parents=True, exist_ok=True)

    def render(spp, seed):
        t0 = time.perf_counter()
        img = mi.render(scene, spp=spp, seed=seed)
        dr.eval(img)
        dr.sync_thread()
        return img, time.perf_counter() - t0

    try:
        _, warm = render(min(args.spp), args.seed + 1_000_000)
        out("info warmup_s", f"{warm:.6f}")
        log(f"mitsuba {args.variant}: warm-up render ({min(args.spp)} spp, untimed) {warm:.3f} s")
        for i, spp in enumerate(args.spp):
            img, secs = render(spp, args.seed + i)
            rgb = base_rgb(np.array(img, dtype=np.float32), 0)
            write_exr(mi, out_dir / f"spp{spp}.exr", rgb,
                      {"variant": args.variant, "spp": spp, "seed": args.seed + i,
                       "render_time_s": secs, "scene": scene_path.name})
            out("point", spp, f"{secs:.6f}")
    except Exception as e:  # noqa: BLE001
        fail(f"Mitsuba render failed: {e}", code=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
