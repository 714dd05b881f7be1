#!/usr/bin/env python3
"""Loads a scene with Mitsuba 3 (scalar_rgb) and renders it once: the Mitsuba side of the
mesh-loading benchmark (see make_load_scenes.py). Prints the seconds of `load_file` and of the
render; `--import-only` times nothing but the import, to subtract from a whole-process time.

    .venv/bin/python references/load_mitsuba.py /tmp/load/ply.xml
"""
import sys
import time

import mitsuba as mi

mi.set_variant("scalar_rgb")
if "--import-only" in sys.argv:
    sys.exit(0)
t0 = time.perf_counter()
scene = mi.load_file(sys.argv[1])
t1 = time.perf_counter()
mi.render(scene)
t2 = time.perf_counter()
print(f"load {t1 - t0:.3f} s, render {t2 - t1:.3f} s")
