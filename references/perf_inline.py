#!/usr/bin/env python3
"""Where the render loop's time goes, by inlined function.

pt's per-sample work is inlined into one function per instruction set (`pt_render::isa::run_v3`,
see crates/pt-render/src/isa.rs), so `perf report --sort sym` shows one symbol for most of a
render. This script resolves each sample's address inside it to its chain of inlined frames
(`llvm-addr2line -i`, from the release build's debug information) and sums the samples by what
they were doing.

    perf record -F 2000 -o /tmp/p.data target/release/pt render SCENE.xml -o /tmp/o.exr
    python3 references/perf_inline.py /tmp/p.data target/release/pt            # by class
    python3 references/perf_inline.py /tmp/p.data target/release/pt --within splat_taken
    python3 references/perf_inline.py /tmp/p.data target/release/pt --top 25   # raw chains

Percentages are of all samples of the recording (kernel and outlined functions included), so
they add up with `perf report`'s. Needs `perf`, `readelf` and `llvm-addr2line` on the PATH.
"""

import argparse
import collections
import re
import subprocess

# A sample belongs to the first class whose pattern matches one of its inlined frames' names
# (regular expressions; inlined frames carry their short names, with generic arguments).
CLASSES = [
    (r"walk<pt_render::accel::wide::Nearest", "closest-hit traversal (wide BVH)"),
    (r"walk<pt_render::accel::wide::Blocked", "any-hit traversal (wide BVH)"),
    (r"^flat_closest", "closest-hit, flat primitive blocks"),
    (r"^flat_any", "any-hit, flat primitive blocks"),
    (r"^closest_batch", "closest-hit batch set-up"),
    (r"^any_batch", "any-hit batch set-up"),
    (r"interaction$", "hit records"),
    (r"^splat_taken", "film: splatting"),
    (r"^put$", "film: samples into pixels"),
    (r"^sample_ray$|^own_pixel_ray$", "camera rays"),
    (r"^scatter<", "shading and light sampling (scatter)"),
    (r"^arrive", "emission at hits (arrive)"),
]

def run(*args, stdin=None):
    return subprocess.run(args, input=stdin, capture_output=True, text=True, check=True).stdout


def sample_counts(data, binary):
    """Samples per file address of `binary`'s executable segment inside `run_v3`, and the
    recording's total sample count."""
    mmaps = run("perf", "script", "-i", data, "--show-mmap-events")
    line = next(l for l in mmaps.splitlines() if "MMAP" in l and "r-xp " + binary in l)
    start = int(re.search(r"\[0x([0-9a-f]+)\(", line).group(1), 16)
    pgoff = int(re.search(r"@ 0x([0-9a-f]+) ", line).group(1), 16)
    load = next(
        l.split()
        for l in run("readelf", "-lW", binary).splitlines()
        if l.strip().startswith("LOAD") and " R E " in l
    )
    offset, vaddr = int(load[1], 16), int(load[2], 16)
    counts, total = collections.Counter(), 0
    for l in run("perf", "script", "-i", data, "-F", "ip,sym").splitlines():
        parts = l.split(None, 1)
        if len(parts) < 2:
            continue
        total += 1
        if "run_v3" in parts[1]:
            counts[int(parts[0], 16) - start + pgoff + vaddr - offset] += 1
    return counts, total


def inline_frames(binary, addresses):
    """Per address, its inlined frames (function, file:line), innermost first."""
    text = run(
        "llvm-addr2line", "-e", binary, "-a", "-f", "-i", "-C", "-s",
        stdin="\n".join(hex(a) for a in addresses) + "\n",
    )
    frames, current, lines = {}, None, text.splitlines()
    i = 0
    while i < len(lines):
        if lines[i].startswith("0x"):
            current = int(lines[i], 16)
            frames[current] = []
            i += 1
        elif not lines[i].strip():
            i += 1
        else:
            frames[current].append((lines[i], lines[i + 1]))
            i += 2
    return frames


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("data", help="perf.data of a render")
    ap.add_argument("binary", help="the pt binary that was recorded (absolute or as recorded)")
    ap.add_argument("--within", metavar="NAME",
                    help="break down the samples under the outermost frame containing NAME by "
                         "the frames just inside it, with their lines")
    ap.add_argument("--top", type=int, metavar="N", help="the N most sampled chains")
    a = ap.parse_args()
    counts, total = sample_counts(a.data, a.binary)
    frames = inline_frames(a.binary, list(counts))
    pct = lambda n: f"{100 * n / total:6.2f}%"
    print(f"{total} samples, {sum(counts.values())} in run_v3")
    short = lambda name: name.split("::")[-1][:48]
    if a.top:
        for addr, n in counts.most_common(a.top):
            print(pct(n), " <- ".join(short(f) for f, _ in frames[addr][:10]))
        return
    agg = collections.Counter()
    for addr, n in counts.items():
        chain = frames[addr]
        if a.within:
            hits = [k for k, (f, _) in enumerate(chain) if a.within in f]
            if not hits:
                continue
            k = hits[-1]
            agg[" <- ".join(f"{short(f)}@{loc}" for f, loc in chain[max(0, k - 2):k + 1])] += n
        else:
            names = [f for f, _ in chain]
            label = next(
                (c for key, c in CLASSES if any(re.search(key, f) for f in names)),
                "other (path and tile loops)",
            )
            agg[label] += n
    for label, n in agg.most_common(40):
        print(pct(n), label)


if __name__ == "__main__":
    main()
